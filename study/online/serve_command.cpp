#include "online/serve_command.h"

#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <iostream>
#include <mutex>
#include <thread>

#include "cli/checks.h"
#include "cli/main.h"
#include "online/online_server.h"
#include "procedure/config.h"
#include "stimuli/frame_patch.h"

namespace fs = std::filesystem;

namespace penumbra::study_app {

ServeCommand::ServeCommand(CLI::App& app, const CLI::Validator& config_check) {
  command_ = app.add_subcommand("serve", "run the study in participants' browsers: an HTTP server, one session per participant id "
                                         "(docs/study-online.md)");
  command_->add_option("--config", config_, "the study config (a file or a shipped name)")
      ->required()
      ->check(cli::path_given())
      ->transform(config_check);
  command_->add_option("-o,--output", sessions_, "the folder of sessions: one directory per participant id, and .stimuli/ (the rendered PNGs)")
      ->required()
      ->check(cli::path_given());
  command_->add_option("--port", port_, "TCP port (0: any free port; the line 'listening on' says which)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  command_->add_option("--bind", bind_, "the address to listen on (behind a reverse proxy: 127.0.0.1)")->capture_default_str();
  command_->add_option("--web", web_, "the page's static files (default: the build folder's web/, built from web/ with jsPsych from web/node_modules)")
      ->check(cli::path_given());
  command_->add_option("--completion-code", completion_code_,
                       "the code the end screen shows (a participant pool's study code); default: one per session, from its id");
  command_->add_option("--completion-url", completion_url_,
                       "the participant pool's return link on the end screen; {code} is replaced by the completion code");
  command_->add_option("--admin-token", admin_token_,
                       "the admin's status page at /admin?token=TOKEN (sessions, trials, staircases, data quality; /admin.json "
                       "the same as JSON); without it there is none");
  command_->add_option("--frame-cache", frame_cache_,
                       "a frame study's prepared frames (penumbra-study prepare-frames; default: $PENUMBRA_FRAME_CACHE, else "
                       "$XDG_CACHE_HOME/penumbra/frames or ~/.cache/penumbra/frames); serve renders none")
      ->check(cli::path_given());
  command_->add_option("--iti-ms", iti_ms_, "blank between trials (ms)")->capture_default_str()->check(CLI::Range(0.0, 10000.0));
}

int ServeCommand::run() const {
  online::ServerOptions o;
  o.config = procedure::load_config(config_);
  if (o.config.frames.enabled()) {
    // As the lab's windows: the frames are prepared ahead (seconds to minutes each on software GL),
    // never rendered while a participant waits; the server cuts its patches from them at start.
    o.frame_cache = frame_cache_.empty() ? stimuli::default_frame_cache() : frame_cache_;
    const stimuli::FrameCache cache(o.frame_cache, false);
    const std::vector<stimuli::FrameRequest> frames = stimuli::session_frames(o.config);
    std::size_t missing = 0;
    for (const stimuli::FrameRequest& f : frames) missing += cache.cached(f) ? 0 : 1;
    if (missing > 0)
      throw cli::UsageError("serve: " + std::to_string(missing) + " of the " + std::to_string(frames.size()) + " frames of " + o.config.name +
                            " are not in the frame cache " + o.frame_cache.string() + "; render them first: penumbra-study prepare-frames --config " +
                            config_.string() + " --frame-cache " + o.frame_cache.string());
  }
  o.config_file = config_;
  o.sessions_dir = sessions_;
  o.web_dir = web_.empty() ? fs::path(PENUMBRA_WEB_DIR) : web_;
  o.bind = bind_;
  o.port = port_;
  o.completion_code = completion_code_;
  o.completion_url = completion_url_;
  o.iti_ms = iti_ms_;
  o.admin_token = admin_token_;
  if (!admin_token_.empty() && admin_token_.size() < 16)
    throw CLI::ValidationError("--admin-token", "at least 16 characters (it is all that guards the page)");
  if (completion_code_.size() > 64) throw CLI::ValidationError("--completion-code", "at most 64 characters");
  static std::mutex say_m;
  o.say = [](const std::string& line) {
    std::lock_guard lock(say_m);
    std::cout << line << std::endl;
  };
  // SIGINT and SIGTERM stop the server from a thread of their own (sigwait), not in a handler.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  ::signal(SIGPIPE, SIG_IGN);
  online::Server server(o);
  const int port = server.bind();
  std::thread stopper([&] {
    int signal = 0;
    sigwait(&stop_signals, &signal);
    if (signal == SIGINT || signal == SIGTERM) std::cout << "stopping (signal " << signal << ")" << std::endl;
    server.stop();
  });
  std::cout << "penumbra-study serve: " << o.config.name << ", sessions in " << sessions_.string() << std::endl;
  std::cout << "listening on http://" << bind_ << ":" << port << "/ (participant link: http://" << bind_ << ":" << port
            << "/?id=PARTICIPANT)" << std::endl;
  server.listen();
  pthread_kill(stopper.native_handle(), SIGTERM);
  stopper.join();
  return 0;
}

}  // namespace penumbra::study_app
