#include "apps/demo/perceptual.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>


namespace penumbra::demo {

namespace {

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
float linear_to_srgb(float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; }

// RGB of an sRGB-encoded 8-bit frame, decoded to linear.
image::ImageF linear_rgb(const io::Image8& frame) {
  image::ImageF out{frame.width, frame.height, 3, std::vector<float>(static_cast<std::size_t>(frame.width) * frame.height * 3)};
  float table[256];
  for (int v = 0; v < 256; ++v) table[v] = srgb_to_linear(static_cast<float>(v) / 255.0f);
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = table[frame.at(x, y, frame.channels >= 3 ? c : 0)];
  return out;
}

}  // namespace

ShadingBasis shading_basis(shadows::Renderer& renderer, const shadows::ShadowSettings& settings, int width_px, int height_px) {
  // Hard shadows of one small map whose reference depth the bias pulls to the light's near plane:
  // every comparison passes, V = 1. The map's cost is a few milliseconds.
  shadows::ShadowSettings unshadowed = settings;
  unshadowed.technique = shadows::Technique::hard;
  unshadowed.adaptive.enabled = false;
  unshadowed.map.cascades = 1;
  unshadowed.map.resolution_texels = 256;
  unshadowed.map.virtual_pages = shadows::VirtualPages::off;
  unshadowed.map.depth_bias_texels = 1e9f;
  const float ambient = renderer.scene().light.ambient;
  renderer.render(unshadowed, width_px, height_px);
  const io::ImageF v = renderer.read_visibility();
  for (std::size_t p = 0; p < v.pixels.size(); ++p)
    if (v.pixels[p] < 1.0f)
      throw std::runtime_error("the unshadowed frame of the lit frames' shading has visibility " + std::to_string(v.pixels[p]) +
                               " at pixel " + std::to_string(p % static_cast<std::size_t>(width_px)) + ", " +
                               std::to_string(p / static_cast<std::size_t>(width_px)) + " (expected 1 everywhere)");
  const image::ImageF lit = linear_rgb(renderer.read_color());
  renderer.scene().light.ambient = 1.0f;
  renderer.render(unshadowed, width_px, height_px);
  renderer.scene().light.ambient = ambient;
  const image::ImageF albedo = linear_rgb(renderer.read_color());  // albedo · light
  ShadingBasis basis{lit, lit};
  for (std::size_t i = 0; i < lit.pixels.size(); ++i) {
    basis.base.pixels[i] = ambient * albedo.pixels[i];
    basis.direct.pixels[i] = std::max(0.0f, lit.pixels[i] - basis.base.pixels[i]);
  }
  return basis;
}

image::ImageF lit_frame(const ShadingBasis& basis, const io::ImageF& visibility) {
  if (visibility.width != basis.base.width || visibility.height != basis.base.height || visibility.channels != 1)
    throw std::invalid_argument("lit_frame: the visibility is not one channel of the shading's size");
  image::ImageF out{visibility.width, visibility.height, 3, std::vector<float>(basis.base.pixels.size())};
  for (std::size_t p = 0; p < visibility.pixels.size(); ++p) {
    const float v = std::clamp(visibility.pixels[p], 0.0f, 1.0f);
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t i = 3 * p + c;
      out.pixels[i] = std::clamp(basis.base.pixels[i] + v * basis.direct.pixels[i], 0.0f, 1.0f);
    }
  }
  return out;
}

CodeDifference code_difference(const image::ImageF& composed, const io::Image8& rendered) {
  if (composed.width != rendered.width || composed.height != rendered.height || rendered.channels < 3)
    throw std::invalid_argument("code_difference: the frames differ in size or the rendered one is not RGB");
  CodeDifference d;
  for (int y = 0; y < composed.height; ++y)
    for (int x = 0; x < composed.width; ++x) {
      int pixel = 0;
      for (int c = 0; c < 3; ++c)
        pixel = std::max(pixel, std::abs(static_cast<int>(std::lround(255.0f * linear_to_srgb(composed.at(x, y, c)))) - rendered.at(x, y, c)));
      d.max = std::max(d.max, pixel);
      d.above_2 += pixel > 2 ? 1 : 0;
      ++d.pixels;
    }
  return d;
}

bool ObserverSeries::visible() const {
  return std::any_of(frames.begin(), frames.end(), [](const Frame& f) { return f.visible; });
}

double ObserverSeries::p_detect_max() const {
  double m = frames.empty() ? NAN : 0.0;
  for (const Frame& f : frames) m = std::max(m, f.p_detect_max);
  return m;
}

void ObserverSeries::add(const metrics::FrameDetection& d) {
  frames.push_back({d.p_detect_max, d.patches_visible, static_cast<int>(d.patches.size()), d.visible});
  criterion_f = d.criterion_f;
}

double FlipSeries::mean() const {
  if (frames.empty()) return NAN;
  double sum = 0;
  for (const auto& f : frames) sum += f.mean;
  return sum / static_cast<double>(frames.size());
}

}  // namespace penumbra::demo
