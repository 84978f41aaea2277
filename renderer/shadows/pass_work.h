#pragma once
// What each pass of a frame gives the GPU to do, counted by the driver
// (ARB_pipeline_statistics_query): primitives submitted (after the CPU's culling), fragment shader
// invocations (a depth pass's rasterized texels, the shading's pixels) and compute shader
// invocations. Counts, not times: what a GPU pays for, whatever machine measures them. A pass
// that reports its own steps (the virtual map's, the screen-space post passes) is counted per
// step, so the pages' raster (virtual_draw) is not mixed with the camera's (virtual_positions).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <penumbra/gl/objects.h>

namespace penumbra::shadows {

struct PassWork {
  std::string pass;
  std::uint64_t primitives = 0;
  std::uint64_t fragments = 0;
  std::uint64_t compute_invocations = 0;
};

// What a shading pass's shadow lookups read, over the pixels it shaded (each once: the surface the
// pixel shows), counted by the shader itself (read_count.glsl, Renderer::count_shading_reads):
// texture instructions, the texels they touch (a gather or a bilinear fetch: 4, a nearest fetch
// or comparison: 1) and those texels' bytes as stored. Fetches, not memory traffic: a GPU's caches
// serve most of them.
struct ShadowReads {
  std::uint64_t pixels = 0;
  std::uint64_t instructions = 0;
  std::uint64_t texels = 0;
  std::uint64_t bytes = 0;
  double per_pixel(std::uint64_t n) const { return pixels ? static_cast<double>(n) / static_cast<double>(pixels) : 0.0; }
};

// Brackets passes with the three queries; one pass at a time (GL allows one active query per
// target). The queries are reused frame after frame.
class WorkCounter {
 public:
  void begin(const std::string& pass);
  void end();
  // Every pass bracketed since the last collect, with its counts: reads the queries, a wait for
  // the frame's GPU work (for measuring runs).
  std::vector<PassWork> collect();

 private:
  std::vector<std::unique_ptr<gl::Query>> queries_;  // three per pass (primitives, fragments, compute)
  std::vector<std::string> passes_;
  bool open_ = false;
};

}  // namespace penumbra::shadows
