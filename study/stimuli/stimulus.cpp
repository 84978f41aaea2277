#include "stimuli/stimulus.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <stdexcept>
#include <vector>

#include "gl/context.h"
#include "gl/embedded_files.h"
#include "gl/objects.h"
#include "gl/shader_library.h"
#include "sampling/poisson_disk.h"
#include "sampling/random.h"

namespace penumbra::embedded {
std::span<const EmbeddedFile> study_shaders();
}

namespace penumbra::stimuli {

Geometry make_geometry(const StimulusSpec& spec) {
  sampling::Random random(sampling::derive_seed(spec.seed, 0x5717));
  Geometry g;
  const double a = spec.artifact_px;
  g.orientation = static_cast<int>(random.bits() % 8);
  const int quarter = g.orientation % 4;
  const double c = std::cos(quarter * std::numbers::pi / 2), s = std::sin(quarter * std::numbers::pi / 2);
  // glm is column-major: dmat2(col0, col1).
  glm::dmat2 rotation(glm::dvec2(std::round(c), std::round(s)), glm::dvec2(-std::round(s), std::round(c)));
  glm::dmat2 mirror = g.orientation >= 4 ? glm::dmat2(glm::dvec2(-1, 0), glm::dvec2(0, 1)) : glm::dmat2(1.0);
  g.to_canonical = rotation * mirror;

  const glm::dvec2 grid_phase(random.uniform() * a, random.uniform() * a);
  const double u_line = random.uniform();
  if (spec.pattern == Pattern::stair) {
    g.line_m = 1.0;
    g.line_b = (u_line - 0.5) * a;
  } else {
    // Rises half a texel across the stimulus, so it crosses exactly one row of texel centres
    // (the one nearest the centre), at x_c inside the middle half.
    const double y_c = grid_phase.y + 0.5 * a - a * std::round((grid_phase.y + 0.5 * a) / a);
    const double x_c = (u_line - 0.5) * 0.5 * spec.size_px;
    g.line_m = 0.5 * a / spec.size_px;
    g.line_b = y_c - g.line_m * x_c;
  }
  const double radius = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  const int k = static_cast<int>(std::ceil((0.5 * spec.size_px + radius) / a)) + 2;
  g.map_origin_px = grid_phase - glm::dvec2(k * a);
  g.map_texels = 2 * k + 1;
  g.poisson_rotation = random.uniform() * 2 * std::numbers::pi;
  return g;
}

std::uint8_t encode(double linear, Transfer transfer) {
  const double v = std::clamp(linear, 0.0, 1.0);
  double e = v;
  if (transfer == Transfer::srgb) e = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
  if (transfer == Transfer::gamma22) e = std::pow(v, 1 / 2.2);
  return static_cast<std::uint8_t>(std::lround(std::clamp(e, 0.0, 1.0) * 255.0));
}

double decode(std::uint8_t value, Transfer transfer) {
  const double e = value / 255.0;
  if (transfer == Transfer::srgb) return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
  if (transfer == Transfer::gamma22) return std::pow(e, 2.2);
  return e;
}

nlohmann::json to_json(const StimulusSpec& spec, const Geometry& g) {
  return {{"pattern", to_string(spec.pattern)},
          {"artifact_px", spec.artifact_px},
          {"filter_radius_px", spec.filter_radius_px},
          {"contrast", spec.lit_linear},
          {"contrast_meaning", "lit level in linear light, fraction of display white"},
          {"kernel", to_string(spec.kernel)},
          {"poisson_taps", spec.poisson_taps},
          {"size_px", spec.size_px},
          {"seed", spec.seed},
          {"transfer_function", to_string(spec.transfer)},
          {"orientation", g.orientation},
          {"line", {{"m", g.line_m}, {"b", g.line_b}, {"frame", "canonical px, origin at centre, y up; occluder below"}}},
          {"shadow_map", {{"texels", g.map_texels}, {"texel_px", spec.artifact_px},
                          {"origin_px", {g.map_origin_px.x, g.map_origin_px.y}}}},
          {"poisson_rotation_rad", g.poisson_rotation}};
}

namespace {

std::vector<std::pair<std::string, std::string>> study_shader_files() {
  std::vector<std::pair<std::string, std::string>> files;
  for (const auto& f : embedded::study_shaders()) files.emplace_back(std::string(f.name), std::string(f.text));
  return files;
}

// The part of the square [lo, hi]^2 below the line y = m x + b (Sutherland–Hodgman, one plane).
std::vector<glm::vec2> occluder_polygon(double lo, double hi, double m, double b) {
  const std::vector<glm::dvec2> square = {{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}};
  auto inside = [&](glm::dvec2 p) { return p.y - m * p.x - b; };  // < 0: occluded side
  std::vector<glm::vec2> out;
  for (std::size_t i = 0; i < square.size(); ++i) {
    const glm::dvec2 p = square[i], q = square[(i + 1) % square.size()];
    const double fp = inside(p), fq = inside(q);
    if (fp < 0) out.emplace_back(p);
    if ((fp < 0) != (fq < 0)) out.emplace_back(p + (q - p) * (fp / (fp - fq)));
  }
  return out;
}

}  // namespace

struct StimulusRenderer::Impl {
  gl::ShaderLibrary library{study_shader_files()};
  gl::Program occluder = library.program({{GL_VERTEX_SHADER, "occluder.vert"}, {GL_FRAGMENT_SHADER, "occluder.frag"}});
  gl::Program filter = library.program({{GL_VERTEX_SHADER, "fullscreen.vert"}, {GL_FRAGMENT_SHADER, "filter.frag"}});
  gl::Sampler nearest{gl::SamplerDesc{GL_NEAREST, GL_NEAREST, GL_CLAMP_TO_EDGE}};
  gl::VertexArray empty_vao;
};

StimulusRenderer::StimulusRenderer() : impl_(std::make_unique<Impl>()) {}
StimulusRenderer::~StimulusRenderer() = default;

StimulusPair StimulusRenderer::render(const StimulusSpec& spec) { return render(spec, make_geometry(spec)); }

StimulusPair StimulusRenderer::render(const StimulusSpec& spec_in, const Geometry& geometry) {
  validate(spec_in);
  StimulusSpec spec = spec_in;
  spec.filter_radius_px = clamp_filter_radius(spec.filter_radius_px, spec.size_px).filter_radius_px;
  StimulusPair pair;
  pair.geometry = geometry;
  const Geometry& g = pair.geometry;
  const float a = static_cast<float>(spec.artifact_px);
  const float extent = a * static_cast<float>(g.map_texels);

  // Shadow-map pass: the occluder's depth (0) over the cleared receiver-free depth (1).
  gl::Texture depth({GL_DEPTH_COMPONENT32F, g.map_texels, g.map_texels, 1}, "stimulus shadow map");
  const gl::Framebuffer::Attachment depth_att[] = {{&depth, GL_DEPTH_ATTACHMENT}};
  gl::Framebuffer map_fbo(depth_att, "stimulus shadow map");
  const std::vector<glm::vec2> poly =
      occluder_polygon(g.map_origin_px.x - a, g.map_origin_px.x + extent + a, g.line_m, g.line_b);
  gl::Buffer vertices(poly.size() * sizeof(glm::vec2), poly.data());
  gl::VertexArray vao;
  glVertexArrayVertexBuffer(vao.id(), 0, vertices.id(), 0, sizeof(glm::vec2));
  glEnableVertexArrayAttrib(vao.id(), 0);
  glVertexArrayAttribFormat(vao.id(), 0, 2, GL_FLOAT, GL_FALSE, 0);
  glVertexArrayAttribBinding(vao.id(), 0, 0);
  map_fbo.bind();
  glViewport(0, 0, g.map_texels, g.map_texels);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glClearDepth(1.0);
  glClear(GL_DEPTH_BUFFER_BIT);
  impl_->occluder.use();
  glProgramUniform2f(impl_->occluder.id(), impl_->occluder.location("u_map_origin_px"),
                     static_cast<float>(g.map_origin_px.x), static_cast<float>(g.map_origin_px.y));
  glProgramUniform1f(impl_->occluder.id(), impl_->occluder.location("u_map_extent_px"), extent);
  vao.bind();
  if (poly.size() >= 3) glDrawArrays(GL_TRIANGLE_FAN, 0, static_cast<GLsizei>(poly.size()));
  glDisable(GL_DEPTH_TEST);

  std::vector<float> depth_values(static_cast<std::size_t>(g.map_texels) * g.map_texels);
  glGetTextureImage(depth.id(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(depth_values.size() * 4),
                    depth_values.data());
  last_map_.resize(depth_values.size());
  for (std::size_t i = 0; i < depth_values.size(); ++i) last_map_[i] = depth_values[i] < 0.5f ? 0 : 1;

  // Receiver pass, twice: from the shadow map, and from the original edge.
  const int n = spec.size_px;
  gl::Texture color({GL_R32F, n, n, 1}, "stimulus visibility");
  const gl::Framebuffer::Attachment color_att[] = {{&color, GL_COLOR_ATTACHMENT0}};
  gl::Framebuffer fbo(color_att, "stimulus visibility");
  const gl::Program& p = impl_->filter;
  const GLuint id = p.id();
  glProgramUniform1i(id, p.location("u_depth"), 0);
  glProgramUniform2f(id, p.location("u_map_origin_px"), static_cast<float>(g.map_origin_px.x),
                     static_cast<float>(g.map_origin_px.y));
  glProgramUniform1f(id, p.location("u_texel_px"), a);
  glProgramUniform1i(id, p.location("u_map_texels"), g.map_texels);
  glProgramUniform2f(id, p.location("u_size_px"), static_cast<float>(n), static_cast<float>(n));
  const glm::mat2 to_canonical(g.to_canonical);
  glProgramUniformMatrix2fv(id, p.location("u_to_canonical"), 1, GL_FALSE, &to_canonical[0][0]);
  glProgramUniform1f(id, p.location("u_radius_px"), static_cast<float>(spec.filter_radius_px));
  glProgramUniform1i(id, p.location("u_kernel"), static_cast<int>(spec.kernel));
  glProgramUniform2f(id, p.location("u_line"), static_cast<float>(g.line_m), static_cast<float>(g.line_b));
  std::vector<glm::vec2> taps = sampling::poisson_disk(spec.poisson_taps);
  const float cr = static_cast<float>(std::cos(g.poisson_rotation)), sr = static_cast<float>(std::sin(g.poisson_rotation));
  for (auto& t : taps) t = glm::vec2(cr * t.x - sr * t.y, sr * t.x + cr * t.y);
  glProgramUniform2fv(id, p.location("u_taps"), static_cast<GLsizei>(taps.size()), &taps[0].x);
  glProgramUniform1i(id, p.location("u_tap_count"), static_cast<int>(taps.size()));
  depth.bind(0);
  impl_->nearest.bind(0);
  fbo.bind();
  glViewport(0, 0, n, n);
  p.use();
  impl_->empty_vao.bind();

  auto draw = [&](int source, io::ImageF& vis, io::Image8& img) {
    glProgramUniform1i(id, p.location("u_source"), source);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    std::vector<float> rows(static_cast<std::size_t>(n) * n);
    glGetTextureImage(color.id(), 0, GL_RED, GL_FLOAT, static_cast<GLsizei>(rows.size() * 4), rows.data());
    vis = {n, n, 1, std::vector<float>(rows.size())};
    img = {n, n, 1, std::vector<std::uint8_t>(rows.size())};
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const float v = rows[static_cast<std::size_t>(n - 1 - y) * n + x];  // GL rows are bottom first
        vis.at(x, y) = v;
        img.at(x, y) = encode(spec.lit_linear * v, spec.transfer);
      }
    }
  };
  draw(0, pair.artifact_visibility, pair.artifact);
  draw(1, pair.line_visibility, pair.line);
  glBindSampler(0, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  gl::check_errors("stimulus render");
  return pair;
}

}  // namespace penumbra::stimuli
