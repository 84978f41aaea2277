#pragma once
// The C++ side of the C++/GLSL contract (shaders/shadow_contract.h): the texture units, binding
// points and the std140 ShadowFrame block, plus the checks that a linked program agrees with it and
// with the virtual shadow map's VirtualFrame block (shaders/virtual_mark_contract.h).
#include <string_view>

#include <penumbra/gl/objects.h>
#include <penumbra/shaders/shadow_contract.h>
#include <penumbra/shaders/virtual_mark_contract.h>

namespace penumbra::shadows {

// Throws std::runtime_error naming `what` when `program` declares the ShadowFrame block with a size
// other than sizeof(contract::ShadowFrame) or at another binding point; programs without the block
// pass.
void check_shadow_frame_block(const gl::Program& program, std::string_view what);
// The same for the VirtualFrame block: sizeof(virtual_mark::VirtualFrame) bytes at binding
// BLOCK_VIRTUAL_FRAME; programs without the block pass.
void check_virtual_frame_block(const gl::Program& program, std::string_view what);

}  // namespace penumbra::shadows
