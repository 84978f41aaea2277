#include "stimuli/frame_patch.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "gl/context.h"
#include "io/atomic_file.h"
#include "json/json_input.h"
#include "scene/scene.h"
#include "shadows/renderer.h"
#include "text/fingerprint.h"

namespace penumbra::stimuli {

namespace fs = std::filesystem;

namespace {

FrameRequest frame_common(const procedure::StudyConfig& config, int round, int patch) {
  const procedure::FramesConfig& f = config.frames;
  FrameRequest r;
  r.scene = f.scene;
  r.width_px = f.width_px;
  r.height_px = f.height_px;
  r.path_frame = f.patches.at(static_cast<std::size_t>(patch)).path_frame;
  r.technique = config.rounds.at(static_cast<std::size_t>(round)).technique;
  r.settings = f.settings;
  r.warmup_frames = f.warmup_frames;
  return r;
}

}  // namespace

FrameRequest test_frame(const procedure::StudyConfig& config, int round, int patch, double k) {
  FrameRequest r = frame_common(config, round, patch);
  r.c = k * config.frames.c;
  return r;
}

FrameRequest reference_frame(const procedure::StudyConfig& config, int round, int patch) {
  // The rule at reference.k is a test frame like the others (the same fingerprint: one render).
  if (config.frames.reference_k > 0) return test_frame(config, round, patch, config.frames.reference_k);
  FrameRequest r = frame_common(config, round, patch);
  r.reference = true;
  r.reference_cascades = config.frames.reference_cascades;
  r.reference_texels = config.frames.reference_texels;
  return r;
}

nlohmann::json to_json(const FrameRequest& r) {
  nlohmann::json settings = nlohmann::json::object();
  for (const auto& [key, value] : r.settings) settings[key] = value;
  nlohmann::json j = {{"scene", r.scene}, {"width_px", r.width_px}, {"height_px", r.height_px}, {"path_frame", r.path_frame},
                      {"technique", r.technique}, {"settings", settings}, {"warmup_frames", r.warmup_frames}};
  if (r.reference) j["reference"] = {{"cascades", r.reference_cascades}, {"resolution_texels", r.reference_texels}};
  else j["rule"] = {{"c", r.c}};
  return j;
}

std::string fingerprint(const FrameRequest& request) { return text::fnv1a64_hex(to_json(request).dump()); }

shadows::ShadowSettings frame_settings(const FrameRequest& r) {
  using namespace shadows;
  ShadowSettings s;
  try {
    s.technique = technique_from_string(r.technique);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("rounds: technique '" + r.technique + "': " + e.what());
  }
  for (const auto& [key, value] : r.settings) {
    const std::string where = "frames.settings." + key + ": ";
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos) throw std::invalid_argument(where + "expected section.key, e.g. pcf.radius");
    const std::string section = key.substr(0, dot), row_key = key.substr(dot + 1);
    bool found = false;
    auto apply = [&](auto& params) {
      for (const auto& row : settings_table(&params)) {
        if (row.key != row_key) continue;
        try {
          set_from_string(row, params, value);
        } catch (const std::invalid_argument& e) {
          throw std::invalid_argument(where + e.what());
        }
        found = true;
      }
    };
    if (section == "map") apply(s.map);
    else if (section == "adaptive") apply(s.adaptive);
    else for_each_technique_section(s, [&](std::string_view name, auto& params) {
      if (name == section) apply(params);
    });
    if (!found) throw std::invalid_argument(where + "no such setting (penumbra-render --help lists them)");
  }
  if (r.reference) {
    s.adaptive.enabled = false;
    s.map.virtual_pages = VirtualPages::off;
    s.map.cascades = r.reference_cascades;
    s.map.resolution_texels = r.reference_texels;
  } else {
    s.adaptive.enabled = true;
    s.adaptive.visibility = 0;
    s.adaptive.c = static_cast<float>(r.c);
    s.map.cascades = 0;  // as many as the rule needs
  }
  return s;
}

struct FrameCache::Gl {
  gl::HeadlessContext context;
  shadows::Renderer renderer;
  std::string scene_name;
  scene::Scene scene;  // as loaded, before any path frame
  int posed_frame = -2;  // the path frame the renderer's scene is at (-2: none yet)
};

FrameCache::FrameCache(fs::path dir, bool may_render) : dir_(std::move(dir)), may_render_(may_render) {}

bool FrameCache::cached(const FrameRequest& request) const {
  const std::string key = fingerprint(request);
  std::error_code ec;
  return fs::is_regular_file(dir_ / (key + ".png"), ec) && fs::is_regular_file(dir_ / (key + ".json"), ec);
}
FrameCache::~FrameCache() = default;

io::Image8 FrameCache::render(const FrameRequest& request) {
  const shadows::ShadowSettings settings = frame_settings(request);
  if (!gl_) gl_ = std::make_unique<Gl>();
  Gl& g = *gl_;
  if (g.scene_name != request.scene) {
    g.scene = scene::load_scene(request.scene);
    g.scene_name = request.scene;
    g.posed_frame = -2;
  }
  if (g.posed_frame != request.path_frame) {
    scene::Scene posed = g.scene;
    if (request.path_frame >= 0) {
      if (posed.camera_path.empty()) throw std::runtime_error("frames.patches: path_frame: scene '" + posed.name + "' has no camera path");
      if (request.path_frame >= posed.camera_path.frames())
        throw std::runtime_error("frames.patches: path_frame " + std::to_string(request.path_frame) + " is beyond the path's last frame " +
                                 std::to_string(posed.camera_path.frames() - 1));
      posed.camera = posed.camera_path.at(posed.camera, request.path_frame);
      posed = scene::posed_at(posed, request.path_frame);
    }
    g.renderer.set_scene(posed);
    g.posed_frame = request.path_frame;
  }
  // A fresh rule: no hysteresis from the frame before (another k); PCSS's rule reads the
  // requirement the frame before measured, hence the warm-up frames.
  g.renderer.reset_adaptive();
  for (int i = 0; i < request.warmup_frames; ++i) g.renderer.render(settings, request.width_px, request.height_px);
  g.renderer.render(settings, request.width_px, request.height_px);
  const io::Image8 rgba = g.renderer.read_color();
  io::Image8 rgb{rgba.width, rgba.height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(rgba.width) * rgba.height * 3)};
  for (int y = 0; y < rgba.height; ++y)
    for (int x = 0; x < rgba.width; ++x)
      for (int c = 0; c < 3; ++c) rgb.at(x, y, c) = rgba.at(x, y, c);
  ++renders_;
  return rgb;
}

const io::Image8& FrameCache::frame(const FrameRequest& request) {
  const std::string key = fingerprint(request);
  if (const auto it = memory_.find(key); it != memory_.end()) return it->second;
  const fs::path png = dir_ / (key + ".png"), json = dir_ / (key + ".json");
  std::error_code ec;
  io::Image8 image;
  if (cached(request)) {
    image = io::read_image8(png);
    if (image.width != request.width_px || image.height != request.height_px || image.channels < 3)
      throw std::runtime_error(png.string() + ": not the " + std::to_string(request.width_px) + " x " + std::to_string(request.height_px) +
                               " RGB frame its name says (remove it to render it again)");
    ++reads_;
  } else {
    if (!may_render_)
      throw std::runtime_error(png.string() + ": frame not in the cache (" + request.technique + ", path frame " +
                               std::to_string(request.path_frame) + (request.reference ? ", the reference" : "") +
                               "); render the study's frames first: penumbra-study prepare-frames --config CONFIG --frame-cache " +
                               dir_.string());
    image = render(request);
    fs::create_directories(dir_, ec);
    if (ec) throw std::runtime_error(dir_.string() + ": cannot create the frame cache: " + ec.message());
    // The image first, renamed into place, then its request: a frame counts as cached only with both.
    const fs::path partial = dir_ / (key + ".partial-" + std::to_string(::getpid()) + ".png");
    io::write_png(partial, image);
    fs::rename(partial, png, ec);
    if (ec) throw std::runtime_error(png.string() + ": cannot keep the rendered frame: " + ec.message());
    io::write_file_atomic(json, json_input::dump(to_json(request), 2) + "\n");
  }
  return memory_.emplace(key, std::move(image)).first->second;
}

std::vector<FrameRequest> session_frames(const procedure::StudyConfig& config) {
  const procedure::FramesConfig& f = config.frames;
  std::vector<double> grid;
  for (double k = f.round_k(f.k_min); k <= f.k_max * (1 + 1e-12); k = f.round_k(k * std::exp2(1.0 / f.k_steps_per_octave))) {
    grid.push_back(k);
    if (f.round_k(k * std::exp2(1.0 / f.k_steps_per_octave)) <= k) break;  // the grid's top
  }
  std::vector<FrameRequest> out;
  std::vector<std::string> seen;
  for (std::size_t round = 0; round < config.rounds.size(); ++round)
    for (std::size_t patch = 0; patch < f.patches.size(); ++patch) {
      std::vector<FrameRequest> these{reference_frame(config, static_cast<int>(round), static_cast<int>(patch))};
      for (double k : grid) these.push_back(test_frame(config, static_cast<int>(round), static_cast<int>(patch), k));
      for (FrameRequest& r : these) {
        const std::string key = fingerprint(r);
        if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;  // patches of one path frame share it
        seen.push_back(key);
        out.push_back(std::move(r));
      }
    }
  return out;
}

io::Image8 crop(const io::Image8& frame, int x_px, int y_px, int size_px) {
  if (x_px < 0 || y_px < 0 || x_px + size_px > frame.width || y_px + size_px > frame.height)
    throw std::invalid_argument("crop: the patch lies outside the frame");
  io::Image8 out{size_px, size_px, frame.channels,
                 std::vector<std::uint8_t>(static_cast<std::size_t>(size_px) * size_px * frame.channels)};
  for (int y = 0; y < size_px; ++y)
    for (int x = 0; x < size_px; ++x)
      for (int c = 0; c < frame.channels; ++c) out.at(x, y, c) = frame.at(x_px + x, y_px + y, c);
  return out;
}

PatchPair patch_pair(FrameCache& cache, const procedure::StudyConfig& config, const procedure::TrialPlan& plan) {
  const procedure::FramePatch& patch = config.frames.patches.at(static_cast<std::size_t>(plan.staircase));
  const int size = config.stimulus_size_px;
  PatchPair pair;
  pair.reference = crop(cache.frame(reference_frame(config, plan.round, plan.staircase)), patch.x_px, patch.y_px, size);
  pair.test = crop(cache.frame(test_frame(config, plan.round, plan.staircase, plan.k)), patch.x_px, patch.y_px, size);
  return pair;
}

metrics::FrameDetection observe_pair(const PatchPair& pair, const metrics::FrameObserverParams& params) {
  auto as_float = [](const io::Image8& img) {
    image::ImageF f{img.width, img.height, img.channels, std::vector<float>(img.pixels.size())};
    for (std::size_t i = 0; i < img.pixels.size(); ++i) f.pixels[i] = img.pixels[i] / 255.0f;
    return f;
  };
  return metrics::detect_difference(as_float(pair.reference), metrics::Encoding::srgb, as_float(pair.test), metrics::Encoding::srgb, params);
}

fs::path default_frame_cache() {
  if (const char* own = std::getenv("PENUMBRA_FRAME_CACHE"); own && *own) return own;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return fs::path(xdg) / "penumbra" / "frames";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "penumbra" / "frames";
  return fs::temp_directory_path() / "penumbra-frames";
}

}  // namespace penumbra::stimuli
