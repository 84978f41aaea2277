// penumbra-study serve over HTTP (docs/study-online.md): a whole short session by a scripted client
// against the lab's own Session with the same seed and answers; the attacks a participant link
// invites; kill -9 of the server mid-session; and the same session in a real browser (Debian's
// chromium driven by puppeteer-core, tests/study/online_browser_session.mjs) when both are there.
#include <gtest/gtest.h>
#include <httplib.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>
#include <memory>
#include <optional>
#include <set>
#include <string>

#include "app_process.h"
#include "json/json_input.h"
#include "log/trial_log.h"
#include "procedure/config.h"
#include "procedure/session.h"
#include "procedure/session_flow.h"
#include "io/image_io.h"
#include "stimuli/frame_patch.h"
#include "text/fingerprint.h"

namespace fs = std::filesystem;
using penumbra::test::App;
using nlohmann::json;

namespace {

const fs::path kConfig = fs::path(PENUMBRA_TESTS_DIR) / "online_short_config.json";
// A frame study: one patch of small frames, six trials (tests/study/online_frames_config.json).
const fs::path kFramesConfig = fs::path(PENUMBRA_TESTS_DIR) / "online_frames_config.json";

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("penumbra-online-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// The server on 127.0.0.1 and a free port; killed (SIGKILL) when destroyed.
struct ServerProcess {
  std::unique_ptr<App> app;
  int port = 0;
  explicit ServerProcess(const fs::path& sessions, int port_ = 0, const std::vector<std::string>& more = {}, const fs::path& config = kConfig) {
    std::vector<std::string> args{"serve", "--config", config.string(), "-o", sessions.string(),
                                  "--port", std::to_string(port_), "--bind", "127.0.0.1", "--iti-ms", "50"};
    args.insert(args.end(), more.begin(), more.end());
    app = std::make_unique<App>(PENUMBRA_STUDY_EXE, args);
    if (!app->wait_for("listening on http://127.0.0.1:")) throw std::runtime_error("the server did not start: " + app->output());
    const std::string out = app->output();
    port = std::stoi(out.substr(out.find("listening on http://127.0.0.1:") + 30));
  }
  void kill9() { app.reset(); }
};

// A participant's page, scripted: the screens it is shown and what it posts.
struct Participant {
  httplib::Client http;
  std::string id, tab;
  json screen;
  int last_status = 0;
  std::string last_error;  // httplib's, when a request got no response
  std::vector<double> latency_ms;  // of every request
  Participant(int port, std::string id_, std::string tab_ = "tab-scripted-1") : http("127.0.0.1", port), id(std::move(id_)), tab(std::move(tab_)) {
    http.set_read_timeout(60, 0);
  }
  struct Timed {
    std::vector<double>& out;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    ~Timed() { out.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()); }
  };
  int retries = 0;  // requests sent again after no response (a keep-alive connection closed under them)
  // As the page does: a request without a response is sent again on a new connection (a post that
  // did arrive is then refused as stale and the screen read again).
  template <class F>
  httplib::Result send(F&& f) {
    for (int attempt = 0;; ++attempt) {
      const Timed timed{latency_ms};
      httplib::Result r = f();
      if (r || attempt == 2) return r;
      ++retries;
    }
  }
  int get() {
    const auto r = send([&] { return http.Get(("/api/screen?id=" + id + "&tab=" + tab).c_str()); });
    if (!r) {
      last_error = httplib::to_string(r.error());
      return last_status = -1;
    }
    if (r->status == 200) screen = json::parse(r->body);
    return last_status = r->status;
  }
  int post(json body) {
    body["id"] = id;
    body["tab"] = tab;
    if (!body.contains("step")) body["step"] = screen.value("step", "");
    const auto r = send([&] { return http.Post("/api/act", body.dump(), "application/json"); });
    if (!r) {
      last_error = httplib::to_string(r.error());
      return last_status = -1;
    }
    if (r->status == 200) screen = json::parse(r->body);
    return last_status = r->status;
  }
  static json answer_body(const json& screen, const std::string& answer) {
    return {{"action", "answer"}, {"trial", screen["trial"]["number"]}, {"answer", answer}, {"rt_ms", 500.25},
            {"frame_ms", {16.7, 16.6, 16.8, 16.7}}, {"key", answer == "first" ? "f" : "j"}, {"onset_ms", 1000.0}, {"response_ms", 1500.25}};
  }
};

// The answer to trial n: answers[n % size], f = first (left), j = second (right).
std::string answer_for(const std::string& answers, int trial) { return answers[static_cast<std::size_t>(trial) % answers.size()] == 'f' ? "first" : "second"; }

// Plays screens until the end screen or until `stop_after` answers (-1: no limit). Returns the
// answers given.
int play(Participant& p, const std::string& answers, int stop_after = -1, const std::function<void(const json&)>& on_trial = {}) {
  int given = 0;
  for (int guard = 0; guard < 500; ++guard) {
    const std::string s = p.screen.value("screen", "");
    const int retries_before = p.retries;
    int status = 0;
    if (s == "consent") {
      status = p.post({{"action", "agree"}});
    } else if (p.screen.value("needs_intake", false)) {
      status = p.post({{"action", "intake"}, {"answers", {{"age", "30"}, {"vision", "no"}}}});
    } else if (p.screen.value("needs_display", false)) {
      status = p.post({{"action", "display"}, {"px_per_mm", 3.78}, {"viewing_distance_mm", 600}, {"window_width_css_px", 1280},
                       {"window_height_css_px", 800}, {"refresh_hz", 60}, {"device_pixel_ratio", 1}, {"user_agent", "scripted"}});
    } else if (s == "welcome" || s == "round" || s == "break" || s == "feedback") {
      status = p.post({{"action", "continue"}});
    } else if (s == "trial") {
      if (given == stop_after) return given;
      if (on_trial) on_trial(p.screen);
      status = p.post(Participant::answer_body(p.screen, answer_for(answers, p.screen["trial"]["number"].get<int>())));
      ++given;
    } else if (s == "end") {
      return given;
    } else {
      ADD_FAILURE() << "unexpected screen: " << p.screen.dump();
      return given;
    }
    if (status == 409 && p.retries > retries_before && p.get() == 200) continue;  // the first try had arrived
    if (status != 200) {
      ADD_FAILURE() << p.id << ": post on the " << s << " screen: status " << status << " " << p.last_error;
      return given;
    }
  }
  ADD_FAILURE() << "the session did not end";
  return given;
}

// The lab's session with the same config, participant (so the same seed) and answers, written by
// procedure::Session as penumbra-study run writes it.
fs::path lab_session(const fs::path& dir, const std::string& id, const std::string& answers, const fs::path& config_file = kConfig) {
  const penumbra::procedure::StudyConfig config = penumbra::procedure::load_config(config_file);
  json extra = {{"observer_kind", "person"},
                {"config_file", config_file.string()},
                {"presentation_options", {{"kind", "browser"}, {"served_by", "penumbra-study serve"}}},
                {"consent", penumbra::procedure::consent_record(config.text("consent"), penumbra::procedure::utc_now())}};
  penumbra::procedure::Session lab = penumbra::procedure::Session::create(config, dir, id, extra);
  while (const auto plan = lab.next()) lab.record(*plan, answer_for(answers, plan->trial) == "first" ? "left" : "right", 500.25);
  return dir;
}

// trials.csv and session.json of an online session equal the lab's apart from timing and display.
void expect_same_as_lab(const fs::path& online, const fs::path& lab) {
  auto rows = [](const fs::path& d) {
    std::vector<std::string> out;
    const penumbra::trial_log::ReadResult log = penumbra::trial_log::read(d / "trials.csv");
    for (penumbra::trial_log::TrialRow r : log.rows) {
      r.session_id.clear();
      r.utc_time.clear();
      r.rt_ms = 0;
      r.timing.reset();
      out.push_back(penumbra::trial_log::format_row(r, log.layout == penumbra::trial_log::Layout::frames ? log.layout
                                                                                                          : penumbra::trial_log::Layout::current));
    }
    return out;
  };
  const std::vector<std::string> a = rows(online), b = rows(lab);
  ASSERT_FALSE(b.empty());
  EXPECT_EQ(a, b);
  auto session = [](const fs::path& d) {
    json j = penumbra::json_input::read_file(d / "session.json");
    for (const char* k : {"created_utc", "resumed_utc", "session_id", "presentation"}) j.erase(k);
    j["consent"].erase("utc");
    return j;
  };
  EXPECT_EQ(session(online).dump(1), session(lab).dump(1));
}

TEST(OnlineServer, WholeSessionByHttpEqualsTheLabSessionWithTheSameSeedAndAnswers) {
  const fs::path tmp = fresh_dir("whole");
  const std::string token = "admin-token-0123456789";
  ServerProcess server(tmp / "sessions", 0, {"--admin-token", token});
  Participant p(server.port, "P01");
  ASSERT_EQ(p.get(), 200);
  EXPECT_EQ(p.screen["screen"], "consent");
  EXPECT_FALSE(fs::exists(tmp / "sessions" / "P01")) << "nothing is written before consent";
  const std::string answers = "ffjfjjfj";
  const int given = play(p, answers);
  EXPECT_EQ(given, 8);  // 2 practice + 2 rounds x 3
  EXPECT_EQ(p.screen["screen"], "end");
  EXPECT_FALSE(p.screen.value("completion_code", "").empty());
  expect_same_as_lab(tmp / "sessions" / "P01", lab_session(tmp / "lab", "P01", answers));
  // The browser's part: its timing in trials.csv, its display in session.json, its data quality.
  const auto log = penumbra::trial_log::read(tmp / "sessions" / "P01" / "trials.csv");
  for (const auto& r : log.rows) {
    ASSERT_TRUE(r.timing.has_value());
    EXPECT_EQ(r.timing->frames, 4);
    EXPECT_DOUBLE_EQ(r.rt_ms, 500.25);
    EXPECT_EQ(r.timing->dropped_frames, 0);
  }
  const json j = penumbra::json_input::read_file(tmp / "sessions" / "P01" / "session.json");
  EXPECT_EQ(j["observer_kind"], "person");
  ASSERT_TRUE(j["presentation"].is_array());
  EXPECT_EQ(j["presentation"].back()["kind"], "browser");
  EXPECT_NEAR(j["presentation"].back()["pixels_per_degree"].get<double>(), 2 * 600 * std::tan(0.5 * M_PI / 180) * 3.78, 1e-9);
  const json online = penumbra::json_input::read_file(tmp / "sessions" / "P01" / "online.json");
  EXPECT_EQ(online["intake"]["answers"]["age"], "30");
  // The completion code is drawn at random, kept, and shown again on a reload: not the id's hash.
  const std::string code = p.screen.value("completion_code", "");
  EXPECT_EQ(code.size(), 10u);
  EXPECT_EQ(online.value("completion_code", ""), code);
  EXPECT_NE(code, penumbra::text::fnv1a64_hex("completion\nP01").substr(0, 10));
  // The end text is the online one (the config gives none): no experimenter to tell, the code to copy.
  const std::string end_text = p.screen.value("body", "");
  EXPECT_EQ(end_text.find("experimenter"), std::string::npos) << end_text;
  EXPECT_NE(end_text.find("Copy the completion code below"), std::string::npos) << end_text;
  ASSERT_EQ(p.get(), 200);
  EXPECT_EQ(p.screen.value("completion_code", ""), code);
  // The admin's page: the session, its trials and each staircase as the lab's admin view shows them.
  httplib::Client admin("127.0.0.1", server.port);
  EXPECT_EQ(admin.Get("/admin")->status, 404);
  EXPECT_EQ(admin.Get("/admin.json?token=admin-token-012345678X")->status, 404);
  const auto status = admin.Get(("/admin.json?token=" + token).c_str());
  ASSERT_EQ(status->status, 200);
  const json sessions = json::parse(status->body)["sessions"];
  ASSERT_EQ(sessions.size(), 1u);
  EXPECT_EQ(sessions[0]["id"], "P01");
  EXPECT_EQ(sessions[0]["trials"], 8);
  EXPECT_EQ(sessions[0]["screen"], "end screen");
  ASSERT_EQ(sessions[0]["staircases"].size(), 2u);
  for (const auto& sc : sessions[0]["staircases"]) {
    EXPECT_EQ(sc["trials"], 3);
    EXPECT_EQ(sc["state"], "done");
  }
  const auto page = admin.Get(("/admin?token=" + token).c_str());
  ASSERT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<h2>P01</h2>"), std::string::npos);
  fs::remove_all(tmp);
}

// penumbra-study with `args` to its end: its exit status, and its stdout and stderr in `out`.
int run_study(const std::vector<std::string>& args, std::string& out, const fs::path& capture) {
  std::string cmd = PENUMBRA_STUDY_EXE;
  for (const std::string& a : args) cmd += " '" + a + "'";
  const int status = std::system((cmd + " > '" + capture.string() + "' 2>&1").c_str());
  out = penumbra::test::slurp(capture);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A frame study served (docs/study-online.md#frame-studies): refused in one line while its frames
// are not prepared; then a whole session by HTTP whose log equals the lab's with the same seed and
// answers, each trial's three images the patches the lab's window shows (the reference's above
// and on the target's side, the test frame's at the trial's k on the other), and a screen that
// would shrink the patches below one device pixel per patch pixel refused with the distance that
// does not.
TEST(OnlineServer, FrameStudyByHttpShowsTheLabsPatchesAndLogsAsTheLab) {
  const fs::path tmp = fresh_dir("frames");
  const fs::path cache = tmp / "frame-cache";
  std::string out;
  EXPECT_EQ(run_study({"serve", "--config", kFramesConfig.string(), "-o", (tmp / "sessions").string(), "--port", "0", "--frame-cache",
                       cache.string()}, out, tmp / "out.txt"), 2);
  EXPECT_EQ(out, "penumbra-study: serve: 4 of the 4 frames of online-frames are not in the frame cache " + cache.string() +
                     "; render them first: penumbra-study prepare-frames --config " + kFramesConfig.string() + " --frame-cache " +
                     cache.string() + "\n");
  EXPECT_FALSE(fs::exists(tmp / "sessions")) << "refused before anything is written";
  ASSERT_EQ(run_study({"prepare-frames", "--config", kFramesConfig.string(), "--frame-cache", cache.string()}, out, tmp / "out.txt"), 0) << out;

  const std::string token = "admin-token-0123456789";
  auto server = std::make_unique<ServerProcess>(tmp / "sessions", 0, std::vector<std::string>{"--frame-cache", cache.string(), "--admin-token", token},
                                                kFramesConfig);
  EXPECT_NE(server->app->output().find("frames: 4 patches of online-frames in 4 files of " + (tmp / "sessions" / ".stimuli").string() +
                                       " (identical frames share them), 4 cut now from 4 frame(s)"), std::string::npos) << server->app->output();
  const std::string answers = "fjjfjf";
  std::map<int, json> trials;  // each trial's screen, by trial number
  {
    Participant p(server->port, "F01");
    ASSERT_EQ(p.get(), 200);
    EXPECT_EQ(p.screen["screen"], "consent");
    EXPECT_EQ(play(p, answers, -1, [&](const json& screen) { trials[screen["trial"]["number"].get<int>()] = screen; }), 6);
    EXPECT_EQ(p.screen["screen"], "end");
  }
  expect_same_as_lab(tmp / "sessions" / "F01", lab_session(tmp / "lab", "F01", answers, kFramesConfig));
  // The admin's page names the staircase's estimate a k (the intensity is log10(1 / k)), not an r/a.
  httplib::Client admin("127.0.0.1", server->port);
  const auto status = admin.Get(("/admin.json?token=" + token).c_str());
  ASSERT_TRUE(status && status->status == 200);
  const json staircase = json::parse(status->body)["sessions"][0]["staircases"][0];
  EXPECT_EQ(staircase["staircase"], "box");
  EXPECT_NEAR(staircase["k"].get<double>(), std::pow(10.0, -staircase["mean"].get<double>()), 1e-12) << staircase;
  EXPECT_FALSE(staircase.contains("r_over_a")) << staircase;
  const auto page = admin.Get(("/admin?token=" + token).c_str());
  ASSERT_TRUE(page && page->status == 200);
  EXPECT_NE(page->body.find("<th>patch<th>trials<th>estimate log10(1/k) &plusmn; sd<th>k<th>"), std::string::npos) << page->body;

  // Each trial shows the lab's patches: cut from the frame cache here as the window cuts them.
  const penumbra::procedure::StudyConfig config = penumbra::procedure::load_config(kFramesConfig);
  penumbra::stimuli::FrameCache frames(cache, false);
  const auto log = penumbra::trial_log::read(tmp / "sessions" / "F01" / "trials.csv");
  ASSERT_EQ(log.layout, penumbra::trial_log::Layout::frames);
  ASSERT_EQ(log.rows.size(), 6u);
  ASSERT_EQ(trials.size(), 6u);
  std::set<std::string> tests_shown;
  for (const auto& row : log.rows) {
    const json& trial = trials.at(row.trial)["trial"];
    ASSERT_EQ(trial["images"].size(), 2u);
    const int reference_side = row.target == "left" ? 0 : 1;
    EXPECT_EQ(trial["sample"], trial["images"][reference_side]) << "the reference above and on the target's side";
    auto served = [&](const json& url) { return penumbra::io::read_image8(tmp / "sessions" / ".stimuli" / fs::path(url.get<std::string>()).filename()); };
    penumbra::procedure::TrialPlan plan;
    plan.round = 0;
    plan.staircase = 0;
    plan.k = row.k;
    const penumbra::stimuli::PatchPair lab = penumbra::stimuli::patch_pair(frames, config, plan);
    EXPECT_EQ(served(trial["sample"]).pixels, lab.reference.pixels) << "trial " << row.trial;
    const penumbra::io::Image8 test = served(trial["images"][1 - reference_side]);
    EXPECT_EQ(test.width, 64);
    EXPECT_EQ(test.pixels, lab.test.pixels) << "trial " << row.trial << ", k " << row.k;
    tests_shown.insert(trial["images"][1 - reference_side].get<std::string>());
  }
  EXPECT_GE(tests_shown.size(), 2u) << "the staircase moved k, and the test patch with it";

  // A screen whose pixels per degree would shrink the patches: refused, and what to do said.
  Participant small(server->port, "F02");
  ASSERT_EQ(small.get(), 200);
  ASSERT_EQ(small.post({{"action", "agree"}}), 200);
  ASSERT_EQ(small.post({{"action", "intake"}, {"answers", {{"age", "30"}}}}), 200);
  EXPECT_EQ(small.post({{"action", "display"}, {"px_per_mm", 1.5}, {"viewing_distance_mm", 300}, {"window_width_css_px", 1280},
                        {"window_height_css_px", 800}, {"device_pixel_ratio", 1}}), 422);
  EXPECT_NE(server->app->output().find("refused 422 POST /api/act: at your viewing distance your screen would show each pixel of the pictures on "
                                       "0.412 of its own pixels, fewer than the 1 they need: sit farther away (at least 73 cm"), std::string::npos)
      << server->app->output();
  ASSERT_EQ(small.get(), 200);
  EXPECT_TRUE(small.screen["needs_display"].get<bool>()) << "measured again";
  EXPECT_EQ(small.post({{"action", "display"}, {"px_per_mm", 1.5}, {"viewing_distance_mm", 750}, {"window_width_css_px", 1280},
                        {"window_height_css_px", 800}, {"device_pixel_ratio", 1}}), 200);
  EXPECT_FALSE(small.screen["needs_display"].get<bool>());

  // A restart cuts nothing again: the patches are in .stimuli.
  server->kill9();
  server = std::make_unique<ServerProcess>(tmp / "sessions", 0, std::vector<std::string>{"--frame-cache", cache.string()}, kFramesConfig);
  EXPECT_NE(server->app->output().find("frames: 4 patches of online-frames in 4 files of " + (tmp / "sessions" / ".stimuli").string() +
                                       " (identical frames share them), 0 cut now from 0 frame(s)"), std::string::npos) << server->app->output();
  fs::remove_all(tmp);
}

// An edge study's stimulus may be shown shrunk while its smallest artifact (8 px in the test's
// config) keeps at least one device pixel per step, 1/8 device pixel per stimulus pixel: at 0.137
// it is shown (and recorded), at 0.124 refused with the distance that gives 1/8.
TEST(OnlineServer, EdgeStimuliShrunkAreShownWhileTheSmallestStepKeepsADevicePixel) {
  const fs::path tmp = fresh_dir("shrunk");
  ServerProcess server(tmp / "sessions");
  auto measured = [&](const std::string& id, double px_per_mm) {
    Participant p(server.port, id);
    EXPECT_EQ(p.get(), 200);
    EXPECT_EQ(p.post({{"action", "agree"}}), 200);
    EXPECT_EQ(p.post({{"action", "intake"}, {"answers", {{"age", "30"}}}}), 200);
    return p.post({{"action", "display"}, {"px_per_mm", px_per_mm}, {"viewing_distance_mm", 300}, {"window_width_css_px", 1280},
                   {"window_height_css_px", 800}, {"device_pixel_ratio", 1}});
  };
  EXPECT_EQ(measured("S01", 1.0), 200);
  const json shown = penumbra::json_input::read_file(tmp / "sessions" / "S01" / "session.json")["presentation"].back();
  EXPECT_NEAR(shown["device_px_per_stimulus_px"].get<double>(), 0.1372, 1e-4);
  EXPECT_EQ(shown["least_device_px_per_stimulus_px"], 0.125);
  EXPECT_TRUE(shown["fits"].get<bool>());
  EXPECT_EQ(measured("S02", 0.9), 422);
  EXPECT_NE(server.app->output().find("refused 422 POST /api/act: at your viewing distance your screen would show each pixel of the pictures "
                                      "on 0.124 of its own pixels, fewer than the 0.125 they need: sit farther away (at least 31 cm, the "
                                      "distance was measured at 30 cm)"), std::string::npos)
      << server.app->output();
  fs::remove_all(tmp);
}

TEST(OnlineServer, AttacksAreRefusedWithAStatusAndNothingIsWrittenOutsideTheSession) {
  const fs::path tmp = fresh_dir("attacks");
  const fs::path sessions = tmp / "sessions";
  ServerProcess server(sessions);
  httplib::Client http("127.0.0.1", server.port);
  auto get_status = [&](const std::string& path) {
    const auto r = http.Get(path.c_str());
    return r ? r->status : -1;
  };
  EXPECT_EQ(get_status("/api/screen?id=..%2F..%2Fescape&tab=tab-attack-1"), 400);
  EXPECT_EQ(get_status("/api/screen?id=../escape&tab=tab-attack-1"), 400);
  EXPECT_EQ(get_status("/api/screen?id=a%00b&tab=tab-attack-1"), 400);
  EXPECT_EQ(get_status("/api/screen?id=%C3%A9t%C3%A9&tab=tab-attack-1"), 400);
  EXPECT_EQ(get_status("/api/screen?id=.hidden&tab=tab-attack-1"), 400);
  const int long_id = get_status("/api/screen?id=" + std::string(10000, 'a') + "&tab=tab-attack-1");
  EXPECT_TRUE(long_id == 414 || long_id == 400) << long_id;
  EXPECT_EQ(get_status("/api/screen?id=" + std::string(100, 'a') + "&tab=tab-attack-1"), 400);
  EXPECT_EQ(get_status("/stimuli/..%2Fsessions.png"), 404);  // decoded to a path, not a name: no route
  EXPECT_EQ(get_status("/stimuli/0123456789abcdef.png"), 404);
  EXPECT_EQ(get_status("/../../etc/passwd"), 404);

  Participant p(server.port, "P02", "tab-attack-1");
  ASSERT_EQ(p.get(), 200);
  // Malformed and oversized posts.
  auto raw_post = [&](const std::string& body) {
    const auto r = http.Post("/api/act", body, "application/json");
    return r ? r->status : -1;
  };
  EXPECT_EQ(raw_post("{\"id\": \"P02\", "), 400);
  EXPECT_EQ(raw_post("[1,2,3]"), 400);
  EXPECT_EQ(raw_post(json({{"id", "P02"}, {"tab", "tab-attack-1"}, {"action", "agree"}, {"step", "x"}, {"pad", std::string(100000, 'x')}}).dump()), 413);
  EXPECT_EQ(raw_post(json({{"id", std::string(10000, 'b')}, {"tab", "tab-attack-1"}, {"action", "agree"}}).dump()), 400);
  EXPECT_EQ(raw_post(json({{"id", "P99"}, {"tab", "tab-attack-1"}, {"action", "agree"}, {"step", "x"}}).dump()), 404);
  // An answer before any trial is on screen.
  EXPECT_EQ(p.post(Participant::answer_body({{"trial", {{"number", 0}}}}, "first")), 409);
  ASSERT_EQ(p.post({{"action", "agree"}}), 200);
  // A replayed post: the same step again.
  const json consent_step = {{"action", "agree"}, {"step", "stale-0"}};
  EXPECT_EQ(p.post(consent_step), 409);
  // A second tab for the same id.
  Participant second(server.port, "P02", "tab-attack-2");
  EXPECT_EQ(second.get(), 409);
  play(p, "f", 0);  // up to the first trial
  ASSERT_EQ(p.screen["screen"], "trial");
  const int trial = p.screen["trial"]["number"];
  json wrong = Participant::answer_body(p.screen, "first");
  wrong["trial"] = trial + 1;
  EXPECT_EQ(p.post(wrong), 409) << "an answer for a trial not on screen";
  json bad = Participant::answer_body(p.screen, "first");
  bad["rt_ms"] = -5;
  EXPECT_EQ(p.post(bad), 400);
  bad = Participant::answer_body(p.screen, "first");
  bad["answer"] = "both";
  EXPECT_EQ(p.post(bad), 400);
  const json good = [&] {
    json g = Participant::answer_body(p.screen, "first");
    g["step"] = p.screen["step"];
    return g;
  }();
  ASSERT_EQ(p.post(good), 200);
  EXPECT_EQ(p.post(good), 409) << "a replayed answer";
  EXPECT_EQ(penumbra::trial_log::read(sessions / "P02" / "trials.csv").rows.size(), 1u) << "the replay added no row";
  // Nothing outside SESSIONS_DIR; inside it, the one session and the stimulus cache.
  std::set<std::string> outside, inside;
  for (const auto& e : fs::directory_iterator(tmp)) outside.insert(e.path().filename().string());
  for (const auto& e : fs::directory_iterator(sessions)) inside.insert(e.path().filename().string());
  EXPECT_EQ(outside, (std::set<std::string>{"sessions"}));
  inside.erase("session.lock");  // the server's lock on the folder
  EXPECT_EQ(inside, (std::set<std::string>{".stimuli", "P02"}));
  // Each refusal is a line on the operator's terminal.
  const std::string out = server.app->output();
  EXPECT_NE(out.find("refused 400 GET /api/screen: id '../escape'"), std::string::npos) << out;
  EXPECT_NE(out.find("refused 409 GET /api/screen: id 'P02' is open in another tab"), std::string::npos) << out;
  EXPECT_NE(out.find("refused 409 POST /api/act: step"), std::string::npos) << out;
  // A second server on the same folder of sessions, or on the same port, is refused at start.
  EXPECT_THROW(ServerProcess again(sessions), std::runtime_error);
  EXPECT_THROW(ServerProcess same_port(tmp / "other", server.port), std::runtime_error);
  fs::remove_all(tmp);
}

TEST(OnlineServer, KillNineMidSessionThenRestartContinuesWithNothingLostOrDuplicated) {
  const fs::path tmp = fresh_dir("kill");
  const std::string answers = "jffjfjff";
  auto server = std::make_unique<ServerProcess>(tmp / "sessions");
  {
    Participant p(server->port, "P03");
    ASSERT_EQ(p.get(), 200);
    EXPECT_EQ(play(p, answers, 4), 4);
    ASSERT_EQ(p.screen["screen"], "trial");
  }
  server->kill9();
  EXPECT_EQ(penumbra::trial_log::read(tmp / "sessions" / "P03" / "trials.csv").rows.size(), 4u);
  server = std::make_unique<ServerProcess>(tmp / "sessions");
  Participant p(server->port, "P03");  // the same tab: it reloads after the connection came back
  ASSERT_EQ(p.get(), 200);
  EXPECT_EQ(p.screen["screen"], "welcome") << "the restarted server resumes at the welcome-back screen";
  EXPECT_FALSE(p.screen["needs_display"].get<bool>()) << "the display measured before the crash is kept";
  EXPECT_EQ(play(p, answers), 4);
  EXPECT_EQ(p.screen["screen"], "end");
  const auto rows = penumbra::trial_log::read(tmp / "sessions" / "P03" / "trials.csv").rows;
  ASSERT_EQ(rows.size(), 8u);
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i].trial, static_cast<int>(i));
  expect_same_as_lab(tmp / "sessions" / "P03", lab_session(tmp / "lab", "P03", answers));
  fs::remove_all(tmp);
}

// The resident memory of the process whose command line names `marker` (kB; 0: none found).
long resident_kb(const std::string& marker) {
  for (const auto& e : fs::directory_iterator("/proc")) {
    std::ifstream cmd(e.path() / "cmdline", std::ios::binary);
    const std::string line((std::istreambuf_iterator<char>(cmd)), {});
    if (line.find(marker) == std::string::npos || line.find("serve") == std::string::npos) continue;
    std::ifstream status(e.path() / "status");
    for (std::string l; std::getline(status, l);)
      if (l.rfind("VmRSS:", 0) == 0) return std::stol(l.substr(6));
  }
  return 0;
}

// 50 participants at once, each a whole session on its own connection: every log complete and
// valid. Prints the server's median and p99 latency and its memory per session (not asserted:
// they depend on the machine).
TEST(OnlineServer, FiftyParticipantsAtOnceAllFinishWithCompleteLogs) {
  const fs::path tmp = fresh_dir("load");
  ServerProcess server(tmp / "sessions");
  const long rss_idle_kb = resident_kb((tmp / "sessions").string());
  constexpr int kParticipants = 50;
  std::vector<std::unique_ptr<Participant>> people;
  for (int i = 0; i < kParticipants; ++i) people.push_back(std::make_unique<Participant>(server.port, "L" + std::to_string(i)));
  std::vector<std::thread> threads;
  std::vector<int> answered(kParticipants, 0);
  for (int i = 0; i < kParticipants; ++i)
    threads.emplace_back([&, i] {
      Participant& p = *people[static_cast<std::size_t>(i)];
      if (p.get() == 200) answered[static_cast<std::size_t>(i)] = play(p, i % 2 ? "fj" : "jjf");
    });
  for (auto& t : threads) t.join();
  const long rss_kb = resident_kb((tmp / "sessions").string());
  server.kill9();  // the server holds each session's lock while it runs; the replay below takes it
  std::vector<double> all;
  int retries = 0;
  for (int i = 0; i < kParticipants; ++i) {
    const Participant& p = *people[static_cast<std::size_t>(i)];
    EXPECT_EQ(answered[static_cast<std::size_t>(i)], 8) << p.id;
    EXPECT_EQ(p.screen.value("screen", ""), "end") << p.id;
    const fs::path dir = tmp / "sessions" / p.id;
    const auto log = penumbra::trial_log::read(dir / "trials.csv");
    EXPECT_EQ(log.rows.size(), 8u) << p.id;
    EXPECT_FALSE(log.torn_tail) << p.id;
    EXPECT_NO_THROW(penumbra::procedure::Session::resume(dir)) << p.id << ": the session replays (session.json and log agree)";
    all.insert(all.end(), p.latency_ms.begin(), p.latency_ms.end());
    retries += p.retries;
  }
  std::sort(all.begin(), all.end());
  ASSERT_FALSE(all.empty());
  std::printf("load: %d participants, %zu requests (%d sent again); server latency median %.1f ms, p99 %.1f ms, max %.1f ms; "
              "resident memory %ld kB idle, %ld kB with the sessions open (%.0f kB per session)\n",
              kParticipants, all.size(), retries, all[all.size() / 2], all[all.size() * 99 / 100], all.back(), rss_idle_kb, rss_kb,
              static_cast<double>(rss_kb - rss_idle_kb) / kParticipants);
  fs::remove_all(tmp);
}

// Debian's chromium, node and puppeteer-core from web/node_modules: "" when all are there.
std::string browser_missing() {
  const fs::path puppeteer = fs::path(PENUMBRA_SOURCE_DIR) / "web" / "node_modules" / "puppeteer-core";
  const char* chromium = std::getenv("PENUMBRA_CHROMIUM") ? std::getenv("PENUMBRA_CHROMIUM") : "/usr/bin/chromium";
  if (!fs::exists(chromium) || !fs::exists(puppeteer) || !fs::exists("/usr/bin/node"))
    return "needs Debian's chromium (scripts/setup.sh --test), /usr/bin/node and web/node_modules (npm ci)";
  return "";
}

const fs::path kBrowserSession = fs::path(PENUMBRA_TESTS_DIR) / "online_browser_session.mjs";

// What tests/study/online_browser_session.mjs printed (a line per screen and step) and its exit
// status: participant `id`'s whole session with `server` in the browser, answering `answers`;
// its screenshots in $PENUMBRA_ONLINE_SCREENSHOTS, else in tmp/screens.
struct BrowserSession {
  int status = -1;
  std::string said;
};
BrowserSession take_in_browser(const ServerProcess& server, const fs::path& tmp, const std::string& id, const std::string& answers) {
  const char* keep = std::getenv("PENUMBRA_ONLINE_SCREENSHOTS");
  const fs::path shots = keep ? fs::path(keep) : tmp / "screens";
  const std::string cmd = "timeout 300 node " + kBrowserSession.string() + " 'http://127.0.0.1:" + std::to_string(server.port) + "/?id=" + id +
                          "' '" + shots.string() + "' " + answers + " > " + (tmp / "browser.txt").string() + " 2>&1";
  BrowserSession session;
  session.status = std::system(cmd.c_str());
  session.said = penumbra::test::slurp(tmp / "browser.txt");
  return session;
}

TEST(OnlineServer, RealBrowserTakesAWholeSessionWithKeyPresses) {
  if (const std::string missing = browser_missing(); !missing.empty()) GTEST_SKIP() << missing;
  const fs::path tmp = fresh_dir("browser");
  ServerProcess server(tmp / "sessions", 0, {"--completion-url", "https://pool.example.org/complete?cc={code}"});
  const std::string answers = "fjjffjfj";
  const auto [status, said] = take_in_browser(server, tmp, "B01", answers);
  ASSERT_EQ(status, 0) << said << "\nserver:\n" << server.app->output();
  EXPECT_NE(said.find("end: completion code"), std::string::npos) << said;
  for (const char* screen : {"consent", "intake", "fullscreen", "chinrest-card", "chinrest-blindspot", "trial0", "feedback", "end"})
    EXPECT_NE(said.find(std::string("screen: ") + screen), std::string::npos) << screen << "\n" << said;
  expect_same_as_lab(tmp / "sessions" / "B01", lab_session(tmp / "lab", "B01", answers));
  const json j = penumbra::json_input::read_file(tmp / "sessions" / "B01" / "session.json");
  const json& shown = j["presentation"].back();
  EXPECT_EQ(shown["kind"], "browser");
  EXPECT_GT(shown["pixels_per_degree"].get<double>(), 5);
  EXPECT_GT(shown["refresh_hz"].get<double>(), 10);
  EXPECT_NE(shown["user_agent"].get<std::string>().find("Chrome"), std::string::npos);
  for (const auto& r : penumbra::trial_log::read(tmp / "sessions" / "B01" / "trials.csv").rows) {
    ASSERT_TRUE(r.timing.has_value());
    EXPECT_GE(r.timing->frames, 1);
    EXPECT_GT(r.rt_ms, 0);
  }
  const json online = penumbra::json_input::read_file(tmp / "sessions" / "B01" / "online.json");
  EXPECT_EQ(online["quality"]["page_loads"], 1);
  // The script never leaves fullscreen or the tab; the end screen's own exit and the browser
  // closed after the end are not the participant's.
  EXPECT_EQ(online["quality"]["fullscreen_exits"], 0) << online["quality"];
  EXPECT_EQ(online["quality"]["tab_switches"], 0) << "closing the tab after the end is no switch\n" << online["quality"];
  // The end screen online: what to do here (the pool's link with the code), not the lab's "tell the experimenter".
  const std::string code = online.value("completion_code", "");
  ASSERT_EQ(code.size(), 10u);
  EXPECT_NE(said.find("end link: https://pool.example.org/complete?cc=" + code), std::string::npos) << said;
  EXPECT_NE(said.find("end text: The session is complete: your answers are saved. / Use the link below to return to the participant pool"),
            std::string::npos)
      << said;
  EXPECT_EQ(said.find("experimenter"), std::string::npos) << said;
  // The chinrest's blind spot, measured three times (the script stops the ball three times): each
  // reading recorded, their mean the plugin's viewing distance.
  const json& readings = shown["chinrest"]["blindspot_distances_mm"];
  ASSERT_EQ(readings.size(), 3u) << shown.dump(1);
  double mean = 0;
  for (const auto& d : readings) mean += d.get<double>() / 3;
  EXPECT_NEAR(mean, shown["viewing_distance_mm"].get<double>(), 0.01 * shown["viewing_distance_mm"].get<double>()) << readings;
#ifdef PENUMBRA_FIT_EXE
  // The fitter reads the browser's session like any other: the participant's pixels per degree
  // from the chinrest, and the session's data quality.
  const std::string fit = std::string(PENUMBRA_FIT_EXE) + " " + (tmp / "sessions" / "B01").string() + " -o " + (tmp / "fit").string() +
                          " --bootstrap 0 --no-progress --allow-unusable > " + (tmp / "fit.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(fit.c_str()), 0) << penumbra::test::slurp(tmp / "fit.txt");
  const json report = penumbra::json_input::read_file(tmp / "fit" / "report.json");
  EXPECT_NEAR(report["pixels_per_degree"]["B01"].get<double>(),
              shown["pixels_per_degree"].get<double>() * 96 / shown["stimulus_css_px"].get<double>(), 1e-9);
  const json& quality = report["data_quality"]["sessions"][0];
  EXPECT_EQ(quality["kind"], "browser");
  EXPECT_EQ(quality["browser"].get<std::string>().rfind("HeadlessChrome ", 0), 0u) << quality;
  EXPECT_EQ(quality["device_pixel_ratio"], 1);
  EXPECT_EQ(quality["page_loads"], 1);
  EXPECT_EQ(quality["chinrest_distances_mm"], readings);
  EXPECT_GT(quality["rt_median_ms"].get<double>(), 0);
  EXPECT_NE(penumbra::test::slurp(tmp / "fit.txt").find("data quality (per session"), std::string::npos);
#endif
  if (!std::getenv("PENUMBRA_ONLINE_SCREENSHOTS")) fs::remove_all(tmp);
}

// A frame study in a real browser: the page shows the reference above the two, each patch
// scaled to the participant's pixels per degree (never below one device pixel per patch pixel),
// and the log equals the lab's with the same seed and answers.
TEST(OnlineServer, RealBrowserTakesAFrameStudySession) {
  if (const std::string missing = browser_missing(); !missing.empty()) GTEST_SKIP() << missing;
  const fs::path tmp = fresh_dir("browser-frames");
  const fs::path cache = tmp / "frame-cache";
  std::string out;
  ASSERT_EQ(run_study({"prepare-frames", "--config", kFramesConfig.string(), "--frame-cache", cache.string()}, out, tmp / "out.txt"), 0) << out;
  ServerProcess server(tmp / "sessions", 0, {"--frame-cache", cache.string()}, kFramesConfig);
  const std::string answers = "jffjjf";
  const auto [status, said] = take_in_browser(server, tmp, "G01", answers);
  ASSERT_EQ(status, 0) << said << "\nserver:\n" << server.app->output();
  for (const char* screen : {"consent", "chinrest-blindspot", "trial0", "feedback", "trial5", "end"})
    EXPECT_NE(said.find(std::string("screen: ") + screen), std::string::npos) << screen << "\n" << said;
  // The page's own count of what it showed on a trial: three images, the sample above the two.
  EXPECT_NE(said.find("trial0 images: sample 1, below 2"), std::string::npos) << said;
  expect_same_as_lab(tmp / "sessions" / "G01", lab_session(tmp / "lab", "G01", answers, kFramesConfig));
  const json j = penumbra::json_input::read_file(tmp / "sessions" / "G01" / "session.json");
  const json& shown = j["presentation"].back();
  EXPECT_EQ(shown["kind"], "browser");
  EXPECT_TRUE(shown["fits"].get<bool>());
  EXPECT_GE(shown["device_px_per_stimulus_px"].get<double>(), 1.0) << shown.dump(1);
  const double config_ppd = penumbra::procedure::load_config(kFramesConfig).display.pixels_per_degree();
  EXPECT_NEAR(shown["stimulus_css_px"].get<double>(), 64 * shown["pixels_per_degree"].get<double>() / config_ppd, 1e-9)
      << "the patch spans the visual angle the config's display gives it";
  for (const auto& r : penumbra::trial_log::read(tmp / "sessions" / "G01" / "trials.csv").rows) {
    ASSERT_TRUE(r.timing.has_value());
    EXPECT_GE(r.timing->frames, 1);
  }
  if (!std::getenv("PENUMBRA_ONLINE_SCREENSHOTS")) fs::remove_all(tmp);
}

// A reload while trial 2 is on screen shows trial 2 again; the server killed (SIGKILL) while
// trial 4 is up and started again on the same port: the page reconnects and the session ends with
// every trial once.
TEST(OnlineServer, RealBrowserReloadMidTrialAndServerKillMidSessionLoseNothing) {
  if (const std::string missing = browser_missing(); !missing.empty()) GTEST_SKIP() << missing;
  const fs::path tmp = fresh_dir("browser-kill");
  auto server = std::make_unique<ServerProcess>(tmp / "sessions");
  const int port = server->port;
  const std::string answers = "jjffjfjf";
  App browser("/usr/bin/node", {kBrowserSession.string(),
                                "http://127.0.0.1:" + std::to_string(port) + "/?id=B02", (tmp / "screens").string(), answers, "2"});
  bool up = false;
  for (int tries = 0; tries < 10 && !up; ++tries) up = browser.wait_for("screen: trial4");
  ASSERT_TRUE(up) << browser.output() << "\nserver:\n" << server->app->output();
  server->kill9();
  server = std::make_unique<ServerProcess>(tmp / "sessions", port);
  ASSERT_EQ(browser.wait_exit(std::chrono::seconds(240)), 0) << browser.output() << "\nserver:\n" << server->app->output();
  const std::string said = browser.output();
  EXPECT_NE(said.find("reload on trial 2"), std::string::npos) << said;
  const std::size_t first = said.find("screen: trial2");
  ASSERT_NE(first, std::string::npos) << said;
  EXPECT_NE(said.find("screen: trial2", first + 1), std::string::npos) << "after the reload, trial 2 again\n" << said;
  EXPECT_NE(said.find("end: completion code"), std::string::npos) << said;
  EXPECT_NE(server->app->output().find("B02: trial 7: "), std::string::npos) << "the restarted server took the last answer\n"
                                                                               << server->app->output();
  const auto rows = penumbra::trial_log::read(tmp / "sessions" / "B02" / "trials.csv").rows;
  ASSERT_EQ(rows.size(), 8u);
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i].trial, static_cast<int>(i));
  expect_same_as_lab(tmp / "sessions" / "B02", lab_session(tmp / "lab", "B02", answers));
  const json online = penumbra::json_input::read_file(tmp / "sessions" / "B02" / "online.json");
  EXPECT_EQ(online["quality"]["page_loads"], 2) << "the first load and the reload";
  fs::remove_all(tmp);
}

}  // namespace
