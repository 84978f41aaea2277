#pragma once
// The study online (docs/study-online.md): an HTTP server in the study app that runs each
// participant's session in their browser. Each participant is one procedure::SessionFlow, the
// lab's state machine, so staircases, trial order, the Latin square, practice and breaks stay in
// C++ and the logs are the lab's (trials.csv, session.json, observer kind "person"). The page asks
// for the current screen (JSON), shows it and posts what the participant did; the stimuli are the
// renderer's PNGs, rendered once per stimulus fingerprint into SESSIONS_DIR/.stimuli and served by
// that fingerprint. A frame study's patches are cut at start from the frames prepared in the frame
// cache (penumbra-study prepare-frames, as the lab's windows read them), named by a hash of the
// frame file and the patch, so the server never renders a frame while participants wait.
//
// What a participant can do is bounded here: an id is a short name of [A-Za-z0-9_-] (never a path),
// one tab holds an id at a time (another is refused while the first is alive; a reload of the same
// tab resumes), every post names the screen it answers (a replayed or stale post is refused),
// bodies are small and rate-limited, and nothing is written outside SESSIONS_DIR.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "procedure/config.h"

namespace penumbra::online {

struct ServerOptions {
  procedure::StudyConfig config;
  std::filesystem::path config_file;   // recorded in session.json (config_file)
  std::filesystem::path sessions_dir;  // SESSIONS_DIR: one directory per participant id, and .stimuli/
  std::filesystem::path web_dir;       // the page's static files (index.html, ...)
  std::filesystem::path frame_cache;   // a frame study's prepared frames (stimuli::FrameCache); every one must be there
  std::string bind = "127.0.0.1";
  int port = 8080;                     // 0: any free port (the line "listening on http://HOST:PORT/" says which)
  std::string completion_code;         // "" : one per session, derived from its session id
  std::string completion_url;          // the participant pool's return link; "{code}" is replaced by the code
  double iti_ms = 400;
  std::size_t max_body_bytes = 64 * 1024;  // an answer carries its frame intervals (6000 at most from the page)
  int max_requests_per_second = 40;    // per participant id
  int max_requests_per_second_per_address = 1000;  // behind a reverse proxy every participant has its address
  double tab_lease_s = 20;             // a tab not heard from for this long gives its id up
  std::string admin_token;             // "": no admin page; else /admin?token=... (and /admin.json)
  std::function<void(const std::string& line)> say;  // the operator's terminal
};

// Why `id` cannot name a participant ("" if it can): 1..64 characters of [A-Za-z0-9_-], the first a
// letter or digit. The id names the session directory, so nothing else is let through.
std::string id_problem(const std::string& id);

class Server {
 public:
  explicit Server(ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds (port 0: any free port) and returns the port; throws std::runtime_error when it cannot.
  int bind();
  // Serves until stop(); returns after the last request is answered.
  void listen();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra::online
