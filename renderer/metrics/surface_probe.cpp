#include "metrics/surface_probe.h"

#include <stdexcept>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "gl/context.h"
#include "gl/shader_library.h"
#include "scene/gpu_mesh.h"

namespace penumbra::metrics {
namespace {

// The position transform is written as in shading.vert (same operands, same order) and declared
// invariant there and here, so both programs rasterize exactly the same fragments.
constexpr const char* kVertex = R"(
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_view_projection;
out vec3 v_world;
invariant gl_Position;
void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_world = world.xyz;
  gl_Position = u_view_projection * world;
}
)";

constexpr const char* kFragment = R"(
in vec3 v_world;
uniform float u_object;  // object index + 1
layout(location = 0) out vec4 o_surface;
void main() { o_surface = vec4(v_world, u_object); }
)";

}  // namespace

glm::mat4 camera_view_projection(const scene::Camera& camera, int width_px, int height_px) {
  const float aspect = static_cast<float>(width_px) / static_cast<float>(height_px);
  return camera.projection_matrix(aspect) * camera.view();
}

struct SurfaceProbe::Gpu {
  gl::Program program;
  scene::GpuMeshes meshes;
  int width = 0, height = 0;
  gl::Texture surface, depth;
  gl::Framebuffer fbo;
};

SurfaceProbe::SurfaceProbe(const scene::Scene& scene) : gpu_(std::make_unique<Gpu>()) {
  const gl::ShaderLibrary library({{"probe.vert", kVertex}, {"probe.frag", kFragment}});
  gpu_->program = library.program({{GL_VERTEX_SHADER, "probe.vert"}, {GL_FRAGMENT_SHADER, "probe.frag"}});
  gpu_->meshes = scene::GpuMeshes(scene.objects);
  for (const auto& o : scene.objects) models_.push_back(o.model);
  gl::check_errors("surface probe setup");
}

SurfaceProbe::~SurfaceProbe() = default;

void SurfaceProbe::set_models(const scene::Scene& scene) {
  if (scene.objects.size() != models_.size())
    throw std::invalid_argument("surface probe: " + std::to_string(scene.objects.size()) + " objects, it has " +
                                std::to_string(models_.size()));
  for (std::size_t i = 0; i < models_.size(); ++i) models_[i] = scene.objects[i].model;
}

io::ImageF SurfaceProbe::render(const scene::Camera& camera, int width_px, int height_px) {
  if (width_px < 1 || height_px < 1) throw std::invalid_argument("surface probe: image size must be positive");
  Gpu& g = *gpu_;
  if (g.width != width_px || g.height != height_px) {
    g.fbo = {};
    g.surface = gl::Texture({GL_RGBA32F, width_px, height_px, 1}, "surface probe");
    g.depth = gl::Texture({GL_DEPTH_COMPONENT32F, width_px, height_px, 1}, "surface probe depth");
    const gl::Framebuffer::Attachment att[] = {{&g.surface, GL_COLOR_ATTACHMENT0}, {&g.depth, GL_DEPTH_ATTACHMENT}};
    g.fbo = gl::Framebuffer(att, "surface probe framebuffer");
    g.width = width_px, g.height = height_px;
  }
  g.fbo.bind();
  glViewport(0, 0, width_px, height_px);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  const float nothing[4] = {0, 0, 0, 0}, far_depth = 1;
  glClearBufferfv(GL_COLOR, 0, nothing);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  g.program.use();
  const glm::mat4 vp = camera_view_projection(camera, width_px, height_px);
  glProgramUniformMatrix4fv(g.program.id(), g.program.location("u_view_projection"), 1, GL_FALSE, glm::value_ptr(vp));
  const GLint model = g.program.location("u_model"), object = g.program.location("u_object");
  for (std::size_t i = 0; i < g.meshes.size(); ++i) {
    glProgramUniformMatrix4fv(g.program.id(), model, 1, GL_FALSE, glm::value_ptr(models_[i]));
    glProgramUniform1f(g.program.id(), object, static_cast<float>(i + 1));
    g.meshes[i].draw();
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);

  io::ImageF img{width_px, height_px, 4, std::vector<float>(static_cast<std::size_t>(width_px) * height_px * 4)};
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(g.surface.id(), 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(img.pixels.size() * sizeof(float)), img.pixels.data());
  gl::check_errors("surface probe");
  io::flip_vertical(img);
  return img;
}

}  // namespace penumbra::metrics
