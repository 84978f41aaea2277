#include "online/online_server.h"

#include <fcntl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <future>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "display/display_calibration.h"
#include "gl/context.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/safe_path.h"
#include "json/json_input.h"
#include "log/directory_lock.h"
#include "procedure/session.h"
#include "procedure/session_flow.h"
#include "procedure/session_record.h"
#include "stimuli/frame_patch.h"
#include "stimuli/stimulus.h"
#include "text/fingerprint.h"

namespace fs = std::filesystem;

namespace penumbra::online {

using procedure::Answer;
using procedure::Screen;
using procedure::Session;
using procedure::SessionFlow;

std::string id_problem(const std::string& id) {
  if (id.empty()) return "the id is empty";
  if (id.size() > 64) return "the id is longer than 64 characters";
  for (const char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) return "the id may hold only letters, digits, _ and -";
  }
  if (id.front() == '-' || id.front() == '_') return "the id must start with a letter or a digit";
  return procedure::name_problem(id);
}

namespace {

double steady_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// An error a request earns: its HTTP status and one line for the page and the operator's log.
struct Refusal {
  int status;
  std::string reason;
};

// Whole or not at all: written beside its name and renamed (a killed server leaves no half PNG).
void put_png(const fs::path& dir, const std::string& name, const io::Image8& image) {
  const fs::path tmp = dir / (name + ".partial-" + std::to_string(::getpid()));
  io::write_png(tmp, image);
  fs::rename(tmp, dir / name);
}

// The renderer's stimuli as PNG files in SESSIONS_DIR/.stimuli, one pair per stimulus fingerprint
// (the spec, its geometry, the technique's settings and the display transfer), named by a hash of
// that fingerprint and the image's role, so that a file's name does not say which is the artifact.
// One thread owns the GL context and renders; requests wait for the pair they need.
class StimulusStore {
 public:
  explicit StimulusStore(fs::path dir) : dir_(std::move(dir)) {}
  ~StimulusStore() {
    {
      std::lock_guard lock(m_);
      stopping_ = true;
    }
    cv_.notify_all();
    if (worker_.joinable()) worker_.join();
  }

  struct Names {
    std::string artifact, line;  // file names under dir()
  };
  const fs::path& dir() const { return dir_; }
  int renders() const { return renders_; }

  Names ensure(const stimuli::StimulusSpec& spec) {
    const stimuli::Geometry geometry = stimuli::make_geometry(spec);
    nlohmann::json key = stimuli::to_json(spec, geometry);
    key["technique"] = spec.technique;
    if (!spec.technique.empty()) key["settings"] = shadows::to_json(stimuli::stimulus_settings(spec, geometry.map_texels));
    if (spec.transfer.calibration) key["calibration"] = display::fingerprint(display::to_json(*spec.transfer.calibration));
    const std::string fingerprint = json_input::dump(key);
    const Names names{text::fnv1a64_hex(fingerprint + "\nartifact") + ".png", text::fnv1a64_hex(fingerprint + "\nline") + ".png"};
    std::error_code ec;
    if (fs::is_regular_file(dir_ / names.artifact, ec) && fs::is_regular_file(dir_ / names.line, ec)) return names;
    std::shared_future<void> done;
    {
      std::lock_guard lock(m_);
      auto it = pending_.find(names.artifact);
      if (it == pending_.end()) {
        auto job = std::make_shared<std::promise<void>>();
        it = pending_.emplace(names.artifact, job->get_future().share()).first;
        jobs_.push_back({spec, names, job});
        if (!worker_.joinable()) worker_ = std::thread([this] { work(); });
      }
      done = it->second;
    }
    cv_.notify_all();
    done.get();  // rethrows the render's error
    return names;
  }

 private:
  struct Job {
    stimuli::StimulusSpec spec;
    Names names;
    std::shared_ptr<std::promise<void>> done;
  };

  void work() {
    std::unique_ptr<gl::HeadlessContext> context;
    std::unique_ptr<stimuli::StimulusRenderer> renderer;
    for (;;) {
      Job job;
      {
        std::unique_lock lock(m_);
        cv_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
        if (jobs_.empty()) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      try {
        if (!renderer) {
          context = std::make_unique<gl::HeadlessContext>();
          renderer = std::make_unique<stimuli::StimulusRenderer>();
        }
        const stimuli::StimulusPair pair = renderer->render(job.spec);
        put_png(dir_, job.names.artifact, pair.artifact);
        put_png(dir_, job.names.line, pair.line);
        ++renders_;
        job.done->set_value();
      } catch (...) {
        job.done->set_exception(std::current_exception());
      }
      std::lock_guard lock(m_);
      pending_.erase(job.names.artifact);
    }
  }

  fs::path dir_;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  std::map<std::string, std::shared_future<void>> pending_;
  std::thread worker_;
  bool stopping_ = false;
  std::atomic<int> renders_{0};
};

// A frame study's patches as PNG files in SESSIONS_DIR/.stimuli: every patch of every frame a
// session can show (stimuli::session_frames), cut at start from the frames in the frame cache,
// which the server never renders (a frame costs seconds to minutes on software GL; the lab's
// windows read prepared frames the same way). A patch is named by a hash of its frame's PNG file
// and its place, so a frame rendered again after a change of the renderer gives new names, and
// a name does not say which image is the reference. The patch is the lab's (stimuli::crop of the
// frame, RGB, 8 bits), written once; a restart finds it and reads no frame.
class FramePatches {
 public:
  FramePatches() = default;
  FramePatches(const procedure::StudyConfig& config, const fs::path& cache_dir, const fs::path& dir) {
    const int size = config.stimulus_size_px;
    for (const stimuli::FrameRequest& request : stimuli::session_frames(config)) {
      const stimuli::FrameCache cache(cache_dir, false);
      if (!cache.cached(request))
        throw std::runtime_error("--frame-cache " + cache_dir.string() + ": frame " + stimuli::fingerprint(request) +
                                 " is not there; render the study's frames first: penumbra-study prepare-frames");
      const fs::path png = cache_dir / (stimuli::fingerprint(request) + ".png");
      const std::string frame_hash = text::fnv1a64_hex(io::read_file(png, std::size_t{1} << 30));
      std::vector<std::pair<std::size_t, std::string>> wanted;  // patches of this frame's path frame, not cut yet
      for (std::size_t i = 0; i < config.frames.patches.size(); ++i) {
        const procedure::FramePatch& patch = config.frames.patches[i];
        if (patch.path_frame != request.path_frame) continue;
        const std::string name = text::fnv1a64_hex(frame_hash + "\npatch " + std::to_string(patch.x_px) + " " + std::to_string(patch.y_px) +
                                                    " " + std::to_string(size)) + ".png";
        names_[key(request, i)] = name;
        std::error_code ec;
        if (!fs::is_regular_file(dir / name, ec)) wanted.emplace_back(i, name);
      }
      if (wanted.empty()) continue;
      stimuli::FrameCache reader(cache_dir, false);
      const io::Image8& frame = reader.frame(request);  // checks the frame's size against its request
      for (const auto& [i, name] : wanted) {
        const procedure::FramePatch& patch = config.frames.patches[i];
        put_png(dir, name, stimuli::crop(frame, patch.x_px, patch.y_px, size));
        ++cut_;
      }
      ++frames_read_;
    }
  }
  bool empty() const { return names_.empty(); }
  std::size_t patches() const { return names_.size(); }
  // Frames with the same pixels (the rule's at k beyond its largest maps, say) give the same names.
  std::size_t files() const {
    std::set<std::string> distinct;
    for (const auto& [key, name] : names_) distinct.insert(name);
    return distinct.size();
  }
  int cut() const { return cut_; }
  int frames_read() const { return frames_read_; }

  // The trial's two patches: the reference's and the test frame's at plan.k.
  struct Names {
    std::string reference, test;
  };
  Names of(const procedure::StudyConfig& config, const procedure::TrialPlan& plan) const {
    const auto patch = static_cast<std::size_t>(plan.staircase);
    return {find(stimuli::reference_frame(config, plan.round, plan.staircase), patch),
            find(stimuli::test_frame(config, plan.round, plan.staircase, plan.k), patch)};
  }

 private:
  static std::string key(const stimuli::FrameRequest& request, std::size_t patch) {
    return stimuli::fingerprint(request) + "/" + std::to_string(patch);
  }
  std::string find(const stimuli::FrameRequest& request, std::size_t patch) const {
    const auto it = names_.find(key(request, patch));
    if (it == names_.end())
      throw std::runtime_error("frame " + stimuli::fingerprint(request) + " (" + request.technique + ", path frame " +
                               std::to_string(request.path_frame) + ") is not among the frames of --config: the session's config differs from it");
    return it->second;
  }
  std::map<std::string, std::string> names_;  // frame fingerprint/patch index -> file name
  int cut_ = 0, frames_read_ = 0;
};

// Requests per second from one key (a participant id, a client address).
class RateLimit {
 public:
  explicit RateLimit(int per_second) : per_second_(per_second) {}
  bool allow(const std::string& key) {
    std::lock_guard lock(m_);
    const auto second = static_cast<long long>(steady_s());
    if (second != second_) {
      counts_.clear();
      second_ = second;
    }
    return ++counts_[key] <= per_second_;
  }

 private:
  int per_second_;
  std::mutex m_;
  long long second_ = -1;
  std::map<std::string, int> counts_;
};

// One participant: their flow (the lab's state machine) and what the browser told us.
struct Participant {
  std::mutex m;
  std::string id;
  std::string tab;            // the tab that holds the id (sessionStorage: it survives a reload)
  double tab_seen_s = 0;
  std::string instance;       // this server run's name for the flow: steps from before a restart are stale
  long step = 0;              // the screen's number; every post names the one it answers
  std::unique_ptr<SessionFlow> flow;
  std::optional<stimuli::StimulusSpec> examples;
  bool declined = false;
  nlohmann::json display;     // the browser's display (null: not measured yet)
  nlohmann::json online;      // online.json: intake, data quality
  std::string last_load;      // the page load whose events were counted last, and its last event number
  long last_event = -1;
  // The flow's clock: the server's steady clock, run ahead by the blanks and feedback the browser
  // shows (the flow passes them at once) and by the answers' reaction times.
  double clock_s = 0;
  double advance(double by_s) {
    clock_s = std::max(clock_s, steady_s()) + by_s;
    return clock_s;
  }
};

std::string random_hex(int bytes) {
  static std::mutex m;
  static std::random_device device;
  std::lock_guard lock(m);
  std::string out;
  char b[3];
  for (int i = 0; i < bytes; ++i) {
    std::snprintf(b, sizeof b, "%02x", static_cast<unsigned>(device() & 0xffu));
    out += b;
  }
  return out;
}

// A field of a posted object, checked: a string of at most `max` bytes of printable ASCII.
std::string short_string(const nlohmann::json& body, const char* key, std::size_t max) {
  const auto it = body.find(key);
  if (it == body.end() || !it->is_string()) throw Refusal{400, std::string(key) + ": expected a string"};
  const std::string s = it->get<std::string>();
  if (s.size() > max) throw Refusal{400, std::string(key) + ": longer than " + std::to_string(max) + " bytes"};
  for (const char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) throw Refusal{400, std::string(key) + ": not printable ASCII"};
  return s;
}
double finite_number(const nlohmann::json& body, const char* key, double lo, double hi) {
  const auto it = body.find(key);
  if (it == body.end() || !it->is_number()) throw Refusal{400, std::string(key) + ": expected a number"};
  const double v = it->get<double>();
  if (!std::isfinite(v) || v < lo || v > hi)
    throw Refusal{400, std::string(key) + ": expected a number in [" + json_input::dump(lo) + ", " + json_input::dump(hi) + "]"};
  return v;
}

}  // namespace

struct Server::Impl {
  trial_log::DirectoryLock sessions_lock;  // of SESSIONS_DIR, for the server's life
  ServerOptions o;
  httplib::Server http;
  StimulusStore stimuli;
  FramePatches frame_patches;  // a frame study's (empty otherwise)
  RateLimit per_id, per_address;
  std::mutex participants_m;
  std::map<std::string, std::shared_ptr<Participant>> participants;
  std::size_t max_participants = 10000;

  explicit Impl(ServerOptions options)
      : o(std::move(options)),
        stimuli(o.sessions_dir / ".stimuli"),
        per_id(o.max_requests_per_second),
        per_address(o.max_requests_per_second_per_address) {}

  void say(const std::string& line) const {
    if (o.say) o.say(line);
  }

  // ---- Participants

  std::shared_ptr<Participant> participant(const std::string& id, const std::string& tab, bool open) {
    if (const std::string bad = id_problem(id); !bad.empty()) throw Refusal{400, "id '" + json_input::printable(id.substr(0, 80)) + "': " + bad};
    if (tab.size() < 8 || tab.size() > 64 || id_problem(tab) != "") throw Refusal{400, "tab: expected 8..64 characters of [A-Za-z0-9_-]"};
    if (!per_id.allow("id:" + id)) throw Refusal{429, "too many requests for id '" + id + "'"};
    std::shared_ptr<Participant> p;
    {
      std::lock_guard lock(participants_m);
      auto it = participants.find(id);
      if (it == participants.end()) {
        if (!open) throw Refusal{404, "id '" + id + "': no session open on this server (open the participant link again)"};
        if (participants.size() >= max_participants) throw Refusal{503, "the server holds its most participants"};
        it = participants.emplace(id, std::make_shared<Participant>()).first;
        it->second->id = id;
      }
      p = it->second;
    }
    return p;
  }

  // The tab that may act for the participant: the one that holds the id, or a new one once the
  // holder has been silent for tab_lease_s (a closed tab, a crashed browser).
  void claim(Participant& p, const std::string& tab) {
    const double now = steady_s();
    if (!p.tab.empty() && p.tab != tab && now - p.tab_seen_s < o.tab_lease_s)
      throw Refusal{409, "id '" + p.id + "' is open in another tab; close it, or wait " +
                             std::to_string(static_cast<int>(std::ceil(o.tab_lease_s))) + " s after closing it"};
    if (p.tab != tab && !p.tab.empty()) say(p.id + ": taken over by a new tab (the last one silent for " + std::to_string(static_cast<int>(now - p.tab_seen_s)) + " s)");
    p.tab = tab;
    p.tab_seen_s = now;
  }

  procedure::FlowHooks hooks(Participant& p) {
    procedure::FlowHooks h;
    const std::string id = p.id;
    h.say = [this, id](const std::string& line) { say(id + ": " + line); };
    h.examples = [&p](const stimuli::StimulusSpec& spec) { p.examples = spec; };
    return h;
  }

  procedure::FlowSetup setup(double refresh_hz) {
    procedure::FlowSetup s;
    s.config = o.config;
    s.iti_ms = o.iti_ms;
    s.refresh_hz = refresh_hz;
    return s;
  }

  // The flow of a participant this server run has not seen: their session resumed from its
  // directory (after a restart, or a session of an earlier run), or a new one that starts at the
  // consent screen (nothing is written before consent).
  void start_flow(Participant& p) {
    const fs::path dir = o.sessions_dir / p.id;
    p.instance = random_hex(6);
    std::error_code ec;
    if (fs::exists(dir, ec) || fs::is_symlink(dir, ec)) {
      if (fs::is_symlink(dir, ec) || !fs::is_directory(dir, ec)) throw Refusal{409, "id '" + p.id + "': its session path is not a directory"};
      if (!fs::is_regular_file(dir / "session.json", ec)) throw Refusal{409, "id '" + p.id + "': its directory holds no session"};
      resume(p);
      return;
    }
    procedure::FlowSetup s = setup(0);
    s.participant = p.id;
    s.open = [this, dir](const std::string& participant, const nlohmann::json& consent) {
      nlohmann::json extra = {{"observer_kind", procedure::to_string(procedure::ObserverKind::person)},
                              {"config_file", o.config_file.string()},
                              {"presentation_options", {{"kind", "browser"}, {"served_by", "penumbra-study serve"}}}};
      if (!consent.is_null()) extra["consent"] = consent;
      return Session::create(o.config, dir, participant, extra);
    };
    p.flow = std::make_unique<SessionFlow>(std::move(s), hooks(p), steady_s());
  }

  Session reopen(const Participant& p) const {
    const fs::path dir = o.sessions_dir / p.id;
    return Session::resume(dir, [&](const Session& s) {
      if (s.session_json().value("participant", std::string()) != p.id)
        throw std::runtime_error("session.json: participant: not '" + p.id + "'");
      if (procedure::observer_kind(s.session_json(), (dir / "session.json").string()) != procedure::ObserverKind::person)
        throw std::runtime_error("session.json: observer_kind: not a person's session");
      procedure::check_consent_record(s.session_json(), o.config, (dir / "session.json").string());
    });
  }

  // The flow of an opened session, with the browser's display as last measured in it (a restart
  // does not ask again); a finished session shows its end screen at once.
  void install(Participant& p, Session session, std::optional<double> refresh_hz = std::nullopt) {
    p.display = nullptr;
    const nlohmann::json& j = session.session_json();
    if (j.contains("presentation") && j["presentation"].is_array())
      for (const auto& entry : j["presentation"])
        if (entry.is_object() && entry.value("kind", std::string()) == "browser" && entry.value("fits", false)) p.display = entry;
    const double hz = refresh_hz ? *refresh_hz : p.display.is_object() ? p.display.value("refresh_hz", 0.0) : 0.0;
    const bool finished = !session.next();
    p.flow = std::make_unique<SessionFlow>(std::move(session), setup(hz), hooks(p), steady_s());
    if (finished) p.flow->space();
  }

  void resume(Participant& p) {
    p.flow.reset();  // releases the directory lock of this run's session, if any
    install(p, reopen(p));
    const fs::path dir = o.sessions_dir / p.id;
    std::error_code ec;
    p.online = nlohmann::json::object();
    if (fs::is_regular_file(dir / "online.json", ec)) {
      try {
        p.online = json_input::read_file(dir / "online.json", {.max_bytes = 4 << 20, .max_depth = 8});
      } catch (const std::exception& e) {
        say(p.id + ": online.json unreadable, started afresh: " + e.what());
      }
    }
  }

  void write_online(Participant& p) {
    if (!p.flow || !p.flow->has_session()) return;
    io::write_file_atomic(p.flow->session().dir() / "online.json", json_input::dump(p.online, 2) + "\n");
  }

  // Blank intervals are the browser's to show: the flow passes them at once, and the screen says
  // how long the blank is.
  void settle(Participant& p) {
    if (p.flow && p.flow->screen() == Screen::blank) p.flow->tick(p.advance(o.iti_ms / 1000.0 + 1e-3));
  }

  std::string step_token(const Participant& p) const { return p.instance + "-" + std::to_string(p.step); }

  double pixels_per_degree(const Participant& p) const {
    return p.display.is_object() ? p.display.value("pixels_per_degree", 0.0) : 0.0;
  }

  nlohmann::json screen(Participant& p) {
    settle(p);
    nlohmann::json j;
    j["step"] = step_token(p);
    j["id"] = p.id;
    if (p.declined || !p.flow || p.flow->done()) {
      j["screen"] = p.declined ? "declined" : "closed";
      return j;
    }
    SessionFlow& flow = *p.flow;
    const Screen s = flow.screen();
    const procedure::ScreenText t = flow.text();
    j["screen"] = procedure::name_of(s);
    j["title"] = t.title;
    j["body"] = t.body;
    j["button"] = t.button;
    j["progress"] = t.progress;
    j["round_line"] = t.round_line;
    const bool session = flow.has_session();
    j["needs_display"] = session && !p.display.is_object() && s != Screen::finished;
    j["needs_intake"] = session && !p.online.contains("intake") && s != Screen::finished;
    const procedure::StudyConfig& c = session ? flow.session().config() : o.config;
    j["task"] = c.task;
    j["keys"] = {{"first", {"f", "ArrowLeft"}}, {"second", {"j", "ArrowRight"}}};
    j["stimulus_px"] = c.stimulus_size_px;
    j["config_pixels_per_degree"] = c.display.pixels_per_degree();
    if (const double ppd = pixels_per_degree(p); ppd > 0) j["stimulus_css_px"] = c.stimulus_size_px * ppd / c.display.pixels_per_degree();
    if (s == Screen::consent) {
      j["first"] = t.first;
      j["second"] = t.second;
    }
    if (t.examples && p.examples) {
      const StimulusStore::Names n = stimuli.ensure(*p.examples);
      j["examples"] = {{"jagged", "/stimuli/" + n.artifact}, {"straight", "/stimuli/" + n.line},
                       {"jagged_label", t.jagged_label}, {"straight_label", t.straight_label}};
    }
    if ((s == Screen::trial || s == Screen::feedback) && flow.plan() && c.frames.enabled()) {
      // Match to sample, as the lab's window shows it: the reference above, below it the
      // reference on the target's side and the test frame's patch on the other.
      const procedure::TrialPlan& plan = *flow.plan();
      const FramePatches::Names n = frame_patches.of(c, plan);
      const std::string ref = "/stimuli/" + n.reference, test = "/stimuli/" + n.test;
      j["trial"] = {{"number", plan.trial}, {"practice", plan.practice}, {"images", plan.target == "left" ? nlohmann::json::array({ref, test}) : nlohmann::json::array({test, ref})},
                    {"sample", ref}, {"iti_ms", o.iti_ms}};
    } else if ((s == Screen::trial || s == Screen::feedback) && flow.plan()) {
      const procedure::TrialPlan& plan = *flow.plan();
      const StimulusStore::Names n = stimuli.ensure(plan.stimulus);
      const std::string a = "/stimuli/" + n.artifact, l = "/stimuli/" + n.line;
      nlohmann::json images = c.task == "2afc" ? nlohmann::json::array({plan.target == "left" ? a : l, plan.target == "left" ? l : a})
                                               : nlohmann::json::array({plan.target == "jagged" ? a : l});
      j["trial"] = {{"number", plan.trial}, {"practice", plan.practice}, {"images", images}, {"iti_ms", o.iti_ms}};
    }
    if ((s == Screen::trial || s == Screen::feedback) && flow.plan()) {
      j["question"] = t.question;
      j["first"] = t.first;
      j["second"] = t.second;
      if (s == Screen::feedback) {
        j["feedback"] = t.feedback;
        j["feedback_correct"] = t.feedback_correct;
        j["feedback_ms"] = c.practice.feedback_ms;
      }
    }
    if (s == Screen::finished && session) {
      // A code of its own per session: 10 random hex digits, drawn once and kept in online.json (a
      // reload shows the same). Not derived from the id, which a participant could recompute.
      if (o.completion_code.empty() && !p.online.contains("completion_code")) {
        std::random_device device;
        std::string drawn;
        for (int i = 0; i < 10; ++i) drawn += "0123456789abcdef"[device() % 16];
        p.online["completion_code"] = drawn;
        write_online(p);
      }
      const std::string code = o.completion_code.empty() ? p.online["completion_code"].get<std::string>() : o.completion_code;
      j["completion_code"] = code;
      if (!o.completion_url.empty()) {
        std::string url = o.completion_url;
        if (const auto at = url.find("{code}"); at != std::string::npos) url.replace(at, 6, code);
        j["completion_url"] = url;
      }
      // The lab's default end text asks the participant to tell the experimenter, who is not there
      // online: unless the config gives its own (texts.end), the end screen says what to do here.
      const bool own_text = std::any_of(c.texts.begin(), c.texts.end(), [](const auto& given) { return given.first == "end"; });
      if (!own_text)
        j["body"] = o.completion_url.empty()
                        ? "The session is complete: your answers are saved.\nCopy the completion code below into the study "
                          "page that sent you here, then you may close this tab."
                        : "The session is complete: your answers are saved.\nUse the link below to return to the participant "
                          "pool; it carries your completion code (shown below in case you need to enter it).";
    }
    return j;
  }

  // ---- What the page posts

  void act(Participant& p, const nlohmann::json& body) {
    const std::string action = short_string(body, "action", 32);
    // Events and the intake are not screens: they carry their own numbers.
    if (action == "event") return event(p, body);
    if (short_string(body, "step", 64) != step_token(p))
      throw Refusal{409, "step: not the screen on display (a replayed or stale post); ask for the screen again"};
    if (!p.flow || p.declined || p.flow->done()) throw Refusal{409, "the session is closed"};
    SessionFlow& flow = *p.flow;
    const Screen s = flow.screen();
    if (action == "agree" || action == "decline") {
      if (s != Screen::consent) throw Refusal{409, action + ": no consent screen on display"};
      if (action == "agree") flow.agree();
      else {
        flow.escape();
        p.declined = true;
      }
    } else if (action == "intake") {
      if (!flow.has_session()) throw Refusal{409, "intake: before consent"};
      if (p.online.contains("intake")) throw Refusal{409, "intake: already given"};
      const auto it = body.find("answers");
      if (it == body.end() || !it->is_object() || it->size() > 20) throw Refusal{400, "answers: expected an object of at most 20 fields"};
      nlohmann::json answers = nlohmann::json::object();
      for (const auto& [k, v] : it->items()) {
        if (id_problem(k) != "" || !v.is_string()) throw Refusal{400, "answers: expected names of [A-Za-z0-9_-] with string values"};
        answers[k] = short_string(*it, k.c_str(), 200);
      }
      p.online["intake"] = {{"utc", procedure::utc_now()}, {"answers", answers}};
      write_online(p);
      say(p.id + ": intake recorded");
    } else if (action == "display") {
      display(p, body);
    } else if (action == "continue") {
      if (s == Screen::feedback) {
        flow.tick(p.advance(flow.session().config().practice.feedback_ms / 1000.0 + 1e-3));
      } else if (s == Screen::welcome || s == Screen::round || s == Screen::rest) {
        if (!p.display.is_object()) throw Refusal{409, "continue: the display is not measured yet (post display first)"};
        flow.space();
      } else {
        throw Refusal{409, "continue: nothing to continue on the " + std::string(procedure::name_of(s)) + " screen"};
      }
    } else if (action == "answer") {
      answer(p, body);
    } else {
      throw Refusal{400, "action: expected agree, decline, intake, display, continue, answer or event"};
    }
    ++p.step;
  }

  void answer(Participant& p, const nlohmann::json& body) {
    SessionFlow& flow = *p.flow;
    if (flow.screen() != Screen::trial || !flow.plan()) throw Refusal{409, "answer: no trial on display"};
    const int trial = static_cast<int>(finite_number(body, "trial", 0, 1e9));
    if (trial != flow.plan()->trial) throw Refusal{409, "trial: " + std::to_string(trial) + " is not the trial on display (" + std::to_string(flow.plan()->trial) + ")"};
    const std::string a = short_string(body, "answer", 8);
    if (a != "first" && a != "second") throw Refusal{400, "answer: expected first or second"};
    const double rt_ms = finite_number(body, "rt_ms", 0, 3.6e6);
    const auto frames = body.find("frame_ms");
    if (frames == body.end() || !frames->is_array() || frames->empty() || frames->size() > 20000)
      throw Refusal{400, "frame_ms: expected 1..20000 frame intervals (ms)"};
    std::vector<double> intervals;
    for (const auto& f : *frames) {
      if (!f.is_number() || !std::isfinite(f.get<double>()) || f.get<double>() < 0 || f.get<double>() > 3.6e6)
        throw Refusal{400, "frame_ms: expected intervals in [0, 3600000] ms"};
      intervals.push_back(f.get<double>());
    }
    // The browser's times on the flow's clock: the blank's last frame now, the onset frame 0's
    // interval later, the stimulus frames by the intervals the page measured
    // (requestAnimationFrame), the answer rt_ms after the onset (the key event's timestamp).
    const double blank_s = p.advance(0);
    const double onset_s = blank_s + intervals[0] / 1000.0;
    const double answer_s = onset_s + rt_ms / 1000.0;
    p.clock_s = answer_s;
    flow.swapped(Screen::blank, blank_s);
    flow.swapped(Screen::trial, onset_s);
    double t = onset_s;
    for (std::size_t i = 1; i < intervals.size(); ++i) {
      t = std::min(answer_s, t + intervals[i] / 1000.0);
      flow.swapped(Screen::trial, t);
    }
    const int done = flow.session().trials_done();
    flow.answer(a == "first" ? Answer::first : Answer::second, answer_s);
    if (flow.session().trials_done() != done + 1) throw Refusal{409, "answer: not taken"};
    // The browser's own timestamps beside the lab's log: one JSON line per trial, fsynced.
    nlohmann::json client = {{"trial", trial}, {"key", body.value("key", std::string())}, {"rt_ms", rt_ms}, {"frames", intervals.size()}};
    if (body.contains("onset_ms") && body["onset_ms"].is_number()) client["onset_performance_now_ms"] = body["onset_ms"];
    if (body.contains("response_ms") && body["response_ms"].is_number()) client["response_performance_now_ms"] = body["response_ms"];
    if (body.contains("hidden") && body["hidden"].is_boolean()) client["hidden_during_trial"] = body["hidden"];
    if (body.contains("fullscreen") && body["fullscreen"].is_boolean()) client["fullscreen"] = body["fullscreen"];
    if (client.value("key", std::string()).size() > 16) client["key"] = "";
    append_line(flow.session().dir() / "client_trials.jsonl", json_input::dump(client) + "\n");
  }

  static void append_line(const fs::path& file, const std::string& line) {
    const int fd = io::open_no_follow(file, O_WRONLY | O_APPEND | O_CREAT, 0644, "client_trials.jsonl");
    const int err = io::write_all(fd, line);
    const int synced = err == 0 ? ::fsync(fd) : 0;
    ::close(fd);
    if (err != 0 || synced != 0) throw std::runtime_error(file.string() + ": cannot write");
  }

  void display(Participant& p, const nlohmann::json& body) {
    SessionFlow& flow = *p.flow;
    if (!flow.has_session()) throw Refusal{409, "display: before consent"};
    if (flow.screen() != Screen::welcome || p.display.is_object()) throw Refusal{409, "display: measured already, or not on the welcome screen"};
    const procedure::StudyConfig& c = flow.session().config();
    // The virtual chinrest (Li et al. 2020): CSS pixels per mm from the card, the viewing distance
    // from the blind spot; pixels per degree at the screen centre as the config's display gives it.
    const double px_per_mm = finite_number(body, "px_per_mm", 0.5, 40);
    const double distance_mm = finite_number(body, "viewing_distance_mm", 150, 3000);
    const double width_css = finite_number(body, "window_width_css_px", 100, 20000);
    const double height_css = finite_number(body, "window_height_css_px", 100, 20000);
    const double ppd = 2.0 * distance_mm * std::tan(0.5 * M_PI / 180.0) * px_per_mm;
    const double css = c.stimulus_size_px * ppd / c.display.pixels_per_degree();
    // A frame study shows the sample above the two (the lab's layout): two rows half a patch apart.
    const double need_w = css * (c.task == "2afc" ? 2.5 : 1.0) + 40, need_h = css * (c.frames.enabled() ? 2.5 : 1.0) + 220;
    nlohmann::json d = {{"kind", "browser"},
                        {"px_per_mm", px_per_mm},
                        {"viewing_distance_mm", distance_mm},
                        {"pixels_per_degree", ppd},
                        {"stimulus_css_px", css},
                        {"window_css_px", {width_css, height_css}}};
    for (const char* k : {"device_pixel_ratio", "refresh_hz", "screen_width_css_px", "screen_height_css_px"})
      if (body.contains(k)) d[k] = finite_number(body, k, 0, 100000);
    for (const char* k : {"user_agent", "chinrest"})
      if (body.contains(k)) d[k] = k == std::string("chinrest") ? nlohmann::json(body[k].is_object() && body[k].dump().size() < 2000 ? body[k] : nlohmann::json()) : nlohmann::json(short_string(body, k, 400));
    // Device pixels per stimulus pixel, and the least a stimulus keeps its structure with
    // (docs/study-online.md#shrunk-stimuli): a frame study's patch needs one, since its aliasing is
    // a pixel's (the lab shows patches 1:1); an edge study's stimulus is drawn from its parameters
    // in stimulus pixels, and keeps every step of its jagged edge while the smallest artifact spans
    // one device pixel, so a shrink down to that is shown (and recorded, and reported by
    // penumbra-fit), one below it refused, with the distance that gives enough.
    const double device_px = css / c.stimulus_size_px * (d.contains("device_pixel_ratio") && d["device_pixel_ratio"].get<double>() > 0
                                                              ? d["device_pixel_ratio"].get<double>() : 1.0);
    const double least_device_px =
        c.frames.enabled() || c.artifact_px.empty() ? 1.0 : 1.0 / *std::min_element(c.artifact_px.begin(), c.artifact_px.end());
    d["device_px_per_stimulus_px"] = device_px;
    d["least_device_px_per_stimulus_px"] = least_device_px;
    const bool large_enough = width_css >= need_w && height_css >= need_h;
    const bool sharp_enough = device_px >= least_device_px;
    const bool fits = large_enough && sharp_enough;
    d["fits"] = fits;
    // record_presentation is the Session's, and the flow owns it: the session is reopened (as a
    // restart reopens it) with the display's refresh rate, on the welcome screen it stood at.
    const double refresh_hz = d.value("refresh_hz", 0.0);
    p.flow.reset();
    Session session = reopen(p);
    session.record_presentation(d);
    install(p, std::move(session), fits ? refresh_hz : 0.0);
    if (!sharp_enough) {
      p.display = nullptr;
      char line[400];
      std::snprintf(line, sizeof line, "at your viewing distance your screen would show each pixel of the pictures on %.3g of its own pixels, "
                    "fewer than the %.3g they need: sit farther away (at least %.0f cm, the distance was measured at %.0f cm) or use a screen "
                    "with smaller pixels", device_px, least_device_px, std::ceil(distance_mm * least_device_px / device_px / 10.0), distance_mm / 10.0);
      throw Refusal{422, line};
    }
    if (!large_enough) {
      p.display = nullptr;
      throw Refusal{422, "the window is too small for the stimuli at your viewing distance: it needs " + std::to_string(static_cast<int>(need_w)) +
                             " x " + std::to_string(static_cast<int>(need_h)) + " px, it has " + std::to_string(static_cast<int>(width_css)) + " x " +
                             std::to_string(static_cast<int>(height_css)) + "; enlarge the window (or sit a little closer)"};
    }
    say(p.id + ": display measured: " + json_input::dump(ppd) + " px per degree, refresh " + json_input::dump(refresh_hz) + " Hz");
  }

  // ---- The admin's view: the sessions this server run holds, as the lab's admin view shows one
  // (screen, trials, each staircase's trials, estimate and sd, r/a), with the data quality.
  nlohmann::json status() {
    std::vector<std::shared_ptr<Participant>> all;
    {
      std::lock_guard lock(participants_m);
      for (const auto& [id, p] : participants) all.push_back(p);
    }
    nlohmann::json out = nlohmann::json::array();
    const double now = steady_s();
    for (const auto& shared : all) {
      Participant& p = *shared;
      std::lock_guard lock(p.m);
      nlohmann::json j = {{"id", p.id}, {"tab_silent_s", std::round(now - p.tab_seen_s)}};
      if (p.declined || !p.flow) {
        j["screen"] = p.declined ? "declined consent" : "not started";
        out.push_back(j);
        continue;
      }
      const SessionFlow& flow = *p.flow;
      const procedure::FlowStatus st = flow.status();
      j["screen"] = st.screen;
      j["last_answer"] = st.last_answer;
      if (flow.has_session()) {
        const Session& s = flow.session();
        j["trials"] = s.trials_done();
        j["pixels_per_degree"] = pixels_per_degree(p);
        const nlohmann::json& q = p.online.contains("quality") ? p.online["quality"] : nlohmann::json::object();
        j["fullscreen_exits"] = q.value("fullscreen_exits", 0);
        j["tab_switches"] = q.value("tab_switches", 0);
        j["page_loads"] = q.value("page_loads", 0);
        nlohmann::json staircases = nlohmann::json::array();
        const std::vector<int>& order = s.randomization().round_order;
        for (std::size_t position = 0; position < order.size(); ++position) {
          const int r = order[position];
          for (const auto& sc : s.rounds()[static_cast<std::size_t>(r)])
            staircases.push_back({{"round", position + 1},
                                  {"condition", s.condition(r)},
                                  {"staircase", sc.name},
                                  {"trials", sc.quest.trial_count()},
                                  {"max_trials", s.config().max_trials},
                                  {"mean", sc.quest.mean()},
                                  {"sd", sc.quest.sd()},
                                  // A frame study's intensity is log10(1 / k): its estimate is a k, not an r/a.
                                  {s.config().frames.enabled() ? "k" : "r_over_a", std::pow(10.0, -sc.quest.mean())},
                                  {"state", sc.done ? "done" : sc.quest.trial_count() == 0 ? "not started" : "running"}});
        }
        j["staircases"] = staircases;
      }
      out.push_back(j);
    }
    return out;
  }

  static std::string html_escape(const std::string& s) {
    std::string out;
    for (const char c : s) {
      if (c == '<') out += "&lt;";
      else if (c == '>') out += "&gt;";
      else if (c == '&') out += "&amp;";
      else if (c == '"') out += "&quot;";
      else out += c;
    }
    return out;
  }

  std::string status_html() {
    const nlohmann::json all = status();
    std::string h = "<!doctype html><meta charset=utf-8><meta http-equiv=refresh content=5><title>" + html_escape(o.config.name) +
                    ": sessions</title><style>body{font-family:sans-serif}td,th{padding:2px 8px;text-align:left}"
                    "table{border-collapse:collapse}tr:nth-child(even){background:#eee}</style><h1>" + html_escape(o.config.name) + ": " +
                    std::to_string(all.size()) + " session(s) in this server run</h1>";
    for (const auto& p : all) {
      char line[400];
      std::snprintf(line, sizeof line, "<h2>%s</h2><p>%s; %d trials; %.1f px/deg; fullscreen exits %d, tab switches %d, page loads %d; "
                    "last heard %g s ago; %s</p>", html_escape(p["id"]).c_str(), html_escape(p["screen"]).c_str(), p.value("trials", 0),
                    p.value("pixels_per_degree", 0.0), p.value("fullscreen_exits", 0), p.value("tab_switches", 0), p.value("page_loads", 0),
                    p["tab_silent_s"].get<double>(), html_escape(p.value("last_answer", std::string())).c_str());
      h += line;
      if (!p.contains("staircases")) continue;
      const bool frames = o.config.frames.enabled();
      h += frames ? "<table><tr><th>round<th>technique<th>patch<th>trials<th>estimate log10(1/k) &plusmn; sd<th>k<th></tr>"
                  : "<table><tr><th>round<th>condition<th>staircase<th>trials<th>estimate log10(a/r) &plusmn; sd<th>r/a<th></tr>";
      for (const auto& sc : p["staircases"]) {
        std::snprintf(line, sizeof line, "<tr><td>%d<td>%s<td>%s<td>%d / %d<td>%+.3f &plusmn; %.3f<td>%.2f<td>%s</tr>", sc["round"].get<int>(),
                      html_escape(sc["condition"]).c_str(), html_escape(sc["staircase"]).c_str(), sc["trials"].get<int>(),
                      sc["max_trials"].get<int>(), sc["mean"].get<double>(), sc["sd"].get<double>(), sc[frames ? "k" : "r_over_a"].get<double>(),
                      html_escape(sc["state"]).c_str());
        h += line;
      }
      h += "</table>";
    }
    return h;
  }

  void check_admin(const httplib::Request& req) const {
    const std::string given = req.get_param_value("token");
    unsigned diff = given.size() != o.admin_token.size() ? 1u : 0u;
    for (std::size_t i = 0; i < std::min(given.size(), o.admin_token.size()); ++i)
      diff |= static_cast<unsigned>(given[i] ^ o.admin_token[i]);
    if (o.admin_token.empty() || diff != 0) throw Refusal{404, "no admin page here (--admin-token and ?token=)"};
  }

  void event(Participant& p, const nlohmann::json& body) {
    const std::string load = short_string(body, "load", 64);
    const long n = static_cast<long>(finite_number(body, "n", 0, 1e9));
    const std::string kind = short_string(body, "kind", 32);
    if (kind != "fullscreen_exit" && kind != "tab_hidden" && kind != "tab_visible" && kind != "page_load")
      throw Refusal{400, "kind: expected fullscreen_exit, tab_hidden, tab_visible or page_load"};
    if (load == p.last_load && n <= p.last_event) throw Refusal{409, "event " + std::to_string(n) + ": counted already (a replayed post)"};
    if (!p.flow || !p.flow->has_session()) return;  // nothing is recorded before consent
    p.last_load = load;
    p.last_event = n;
    nlohmann::json& q = p.online["quality"];
    if (!q.is_object()) q = {{"fullscreen_exits", 0}, {"tab_switches", 0}, {"page_loads", 0}, {"events", nlohmann::json::array()}};
    if (kind == "fullscreen_exit") q["fullscreen_exits"] = q.value("fullscreen_exits", 0) + 1;
    if (kind == "tab_hidden") q["tab_switches"] = q.value("tab_switches", 0) + 1;
    if (kind == "page_load") q["page_loads"] = q.value("page_loads", 0) + 1;
    if (q["events"].size() < 2000)
      q["events"].push_back({{"kind", kind}, {"utc", procedure::utc_now()}, {"trials_done", p.flow->session().trials_done()}});
    write_online(p);
  }
};

namespace {

void reply(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(json_input::dump(body), "application/json");
}

bool stimulus_name(const std::string& name) {
  if (name.size() != 20 || name.compare(16, 4, ".png") != 0) return false;
  for (int i = 0; i < 16; ++i)
    if (!((name[i] >= '0' && name[i] <= '9') || (name[i] >= 'a' && name[i] <= 'f'))) return false;
  return true;
}

}  // namespace

Server::Server(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  Impl& s = *impl_;
  std::error_code ec;
  if (!fs::is_regular_file(s.o.web_dir / "index.html", ec))
    throw std::runtime_error("--web " + s.o.web_dir.string() + ": no index.html (install the page: scripts/setup.sh runs npm ci in web/, then build penumbra-study)");
  io::refuse_link(s.o.sessions_dir, "the folder of sessions is named itself, not through a link");
  if (fs::exists(s.o.sessions_dir, ec) && !fs::is_directory(s.o.sessions_dir, ec))
    throw std::runtime_error("-o " + s.o.sessions_dir.string() + ": not a folder");
  fs::create_directories(s.o.sessions_dir / ".stimuli", ec);
  if (ec) throw std::runtime_error("-o " + s.o.sessions_dir.string() + ": cannot create " + (s.o.sessions_dir / ".stimuli").string() + ": " + ec.message());
  if (s.o.config.frames.enabled()) {
    s.frame_patches = FramePatches(s.o.config, s.o.frame_cache, s.stimuli.dir());
    s.say("frames: " + std::to_string(s.frame_patches.patches()) + " patches of " + s.o.config.name + " in " + std::to_string(s.frame_patches.files()) +
          " files of " + s.stimuli.dir().string() + " (identical frames share them), " + std::to_string(s.frame_patches.cut()) + " cut now from " +
          std::to_string(s.frame_patches.frames_read()) + " frame(s) of the frame cache " + s.o.frame_cache.string());
  }
  // One server per folder of sessions: a second one is refused before it listens.
  s.sessions_lock = trial_log::DirectoryLock(s.o.sessions_dir);
  httplib::Server& http = s.http;
  http.new_task_queue = [] { return new httplib::ThreadPool(64); };
  // SO_REUSEADDR (a restart binds while the killed server's connections wait out TIME_WAIT), but
  // not httplib's default SO_REUSEPORT: a second server on the same port is refused, not handed
  // half of the participants' connections.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  http.set_payload_max_length(s.o.max_body_bytes);
  http.set_read_timeout(10, 0);
  http.set_write_timeout(10, 0);
  http.set_keep_alive_max_count(1000);
  http.set_mount_point("/", s.o.web_dir.string());
  http.set_file_extension_and_mimetype_mapping("mjs", "text/javascript");

  // Every request through here: rate-limited per address; a refusal is a status, a JSON reason
  // and one line on the operator's terminal.
  auto guarded = [&s](const char* method, std::function<void(const httplib::Request&, httplib::Response&)> f) {
    return [&s, method, f = std::move(f)](const httplib::Request& req, httplib::Response& res) {
      try {
        if (!s.per_address.allow("addr:" + req.remote_addr)) throw Refusal{429, "too many requests from " + req.remote_addr};
        f(req, res);
      } catch (const Refusal& r) {
        reply(res, r.status, {{"error", r.reason}});
        s.say("refused " + std::to_string(r.status) + " " + method + " " + json_input::printable(req.path.substr(0, 80)) + ": " + r.reason);
      } catch (const std::exception& e) {
        reply(res, 500, {{"error", e.what()}});
        s.say("error 500 " + std::string(method) + " " + json_input::printable(req.path.substr(0, 80)) + ": " + e.what());
      }
    };
  };

  http.Get("/api/screen", guarded("GET", [&s](const httplib::Request& req, httplib::Response& res) {
             const std::shared_ptr<Participant> p = s.participant(req.get_param_value("id"), req.get_param_value("tab"), true);
             std::lock_guard lock(p->m);
             s.claim(*p, req.get_param_value("tab"));
             if (!p->flow && !p->declined) s.start_flow(*p);
             reply(res, 200, s.screen(*p));
           }));
  http.Post("/api/act", guarded("POST", [&s](const httplib::Request& req, httplib::Response& res) {
              nlohmann::json body;
              try {
                body = json_input::parse(req.body, "body", {.max_bytes = s.o.max_body_bytes, .max_depth = 4});
              } catch (const std::exception& e) {
                throw Refusal{400, std::string("malformed JSON: ") + e.what()};
              }
              if (!body.is_object()) throw Refusal{400, "expected a JSON object"};
              const std::string id = short_string(body, "id", 200), tab = short_string(body, "tab", 200);
              const std::shared_ptr<Participant> p = s.participant(id, tab, false);
              std::lock_guard lock(p->m);
              s.claim(*p, tab);
              if (!p->flow && !p->declined) throw Refusal{409, "ask for the screen first"};
              s.act(*p, body);
              reply(res, 200, s.screen(*p));
            }));
  http.Get("/admin", guarded("GET", [&s](const httplib::Request& req, httplib::Response& res) {
             s.check_admin(req);
             res.set_header("Cache-Control", "no-store");
             res.set_content(s.status_html(), "text/html; charset=utf-8");
           }));
  http.Get("/admin.json", guarded("GET", [&s](const httplib::Request& req, httplib::Response& res) {
             s.check_admin(req);
             reply(res, 200, {{"config", s.o.config.name}, {"sessions", s.status()}});
           }));
  http.Get(R"(/stimuli/([^/]*))", guarded("GET", [&s](const httplib::Request& req, httplib::Response& res) {
             const std::string name = req.matches[1];
             if (!stimulus_name(name)) throw Refusal{400, "not a stimulus name"};
             std::string png;
             try {
               png = io::read_file(s.stimuli.dir() / name, 64 << 20, io::Links::refuse);
             } catch (const std::exception&) {
               throw Refusal{404, "no such stimulus"};
             }
             res.set_header("Cache-Control", "public, max-age=31536000, immutable");
             res.set_content(png, "image/png");
           }));
}

Server::~Server() = default;

int Server::bind() {
  Impl& s = *impl_;
  const int port = s.o.port == 0 ? s.http.bind_to_any_port(s.o.bind) : (s.http.bind_to_port(s.o.bind, s.o.port) ? s.o.port : -1);
  if (port <= 0) throw std::runtime_error("--bind " + s.o.bind + " --port " + std::to_string(s.o.port) + ": cannot listen there (in use, or no such address)");
  return port;
}

void Server::listen() { impl_->http.listen_after_bind(); }
void Server::stop() { impl_->http.stop(); }

}  // namespace penumbra::online
