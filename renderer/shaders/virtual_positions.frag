// The camera's surfaces for the virtual shadow map's page marking (virtual_mark.comp): world xyz and
// w = 1 where a surface is (the target is cleared to 0). Drawn with shading.vert, whose invariant
// positions let the shading pass test this pass's depth with LEQUAL.
in vec3 v_world;
in vec3 v_normal;
layout(location = 0) out vec4 o_position;

void main() { o_position = vec4(v_world, 1.0); }
