#pragma once
// A frame study's stimuli (config "frames", docs/study.md#frames-the-rules-own-frames): square
// patches of frames the renderer draws of a scene at a path frame, by the resolution rule with its
// constant c scaled by k (adaptive.c = k c, as many cascades as the rule needs), and the same patch
// of the reference frame (the same technique and filter on frames.reference's cascades, the rule
// off; or, with frames.reference.k, the rule's own frame at that k). A frame is rendered once per settings fingerprint and kept on disk (FrameCache), so a
// session renders only the grid values of k it has not met before and a second session none.
//
// The patches are the renderer's lit colour as it is, sRGB-encoded, 8 bits, RGB: shown 1:1, as a
// game shows its frames (the display's transfer is not applied again).
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/image_io.h"
#include "metrics/frame_observer.h"
#include "procedure/config.h"
#include "procedure/procedure.h"
#include "shadows/settings.h"

namespace penumbra::stimuli {

// Everything that decides a frame's pixels.
struct FrameRequest {
  std::string scene;
  int width_px = 0, height_px = 0;
  int path_frame = -1;
  std::string technique;
  std::vector<std::pair<std::string, std::string>> settings;  // frames.settings
  bool reference = false;
  double c = 0;  // the rule's adaptive.c (k times frames.c); 0 for the reference
  int reference_cascades = 0, reference_texels = 0;  // the reference only
  int warmup_frames = 0;
};
// The request of a trial's test frame (k = plan.k) or of its reference.
FrameRequest test_frame(const procedure::StudyConfig& config, int round, int patch, double k);
FrameRequest reference_frame(const procedure::StudyConfig& config, int round, int patch);
nlohmann::json to_json(const FrameRequest& request);
// FNV-1a 64 of the request's JSON, in hex: the cache's file name.
std::string fingerprint(const FrameRequest& request);
// The renderer settings of a request. Throws std::invalid_argument naming the setting
// ("frames.settings.pcf.radius: ...") or the technique.
shadows::ShadowSettings frame_settings(const FrameRequest& request);

// Renders frames through the renderer (needs a current OpenGL 4.5 context) and keeps each as
// <cache>/<fingerprint>.png with <fingerprint>.json (the request) beside it; a frame already there
// is read, not rendered. Files are written whole (renamed into place), so a killed session leaves
// none half written.
class FrameCache {
 public:
  // `may_render` false: a frame not on disk is an error (the windows, whose GL context is the
  // participant's, read frames prepared before: penumbra-study prepare-frames).
  explicit FrameCache(std::filesystem::path dir, bool may_render = true);
  ~FrameCache();
  FrameCache(const FrameCache&) = delete;
  FrameCache& operator=(const FrameCache&) = delete;

  // The frame's lit colour, RGB, sRGB-encoded, top row first. Throws std::runtime_error naming the
  // scene, frame or setting that cannot be rendered.
  const io::Image8& frame(const FrameRequest& request);
  // Whether the frame is on disk (its image and its request).
  bool cached(const FrameRequest& request) const;
  int renders() const { return renders_; }   // frames rendered by this cache object
  int reads() const { return reads_; }       // frames read from disk
  const std::filesystem::path& dir() const { return dir_; }

 private:
  io::Image8 render(const FrameRequest& request);
  struct Gl;
  std::filesystem::path dir_;
  bool may_render_ = true;
  std::unique_ptr<Gl> gl_;  // the renderer and the loaded scene, made at the first render
  std::map<std::string, io::Image8> memory_;  // this session's frames by fingerprint
  int renders_ = 0, reads_ = 0;
};

// Every frame a session of `config` can show: per round, per path frame of its patches, the
// reference and the rule at every k of the grid.
std::vector<FrameRequest> session_frames(const procedure::StudyConfig& config);

// The square patch of `size_px` at (x_px, y_px) of `frame`.
io::Image8 crop(const io::Image8& frame, int x_px, int y_px, int size_px);

struct PatchPair {
  io::Image8 reference, test;  // RGB, stimulus.size_px square
};
// A trial's two patches (plan.k's frame and the reference), from the cache.
PatchPair patch_pair(FrameCache& cache, const procedure::StudyConfig& config, const procedure::TrialPlan& plan);

// The frame observer's (metrics/frame_observer.h) probability that a participant shown the pair
// picks the reference out: p_correct of the patch's most detectable part (its 2° sub-patches).
metrics::FrameDetection observe_pair(const PatchPair& pair, const metrics::FrameObserverParams& params);

// The default cache folder: $PENUMBRA_FRAME_CACHE, else $XDG_CACHE_HOME/penumbra/frames, else
// ~/.cache/penumbra/frames.
std::filesystem::path default_frame_cache();

}  // namespace penumbra::stimuli
