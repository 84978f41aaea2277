#pragma once
// `penumbra-study serve`: the study online (online_server.h, docs/study-online.md). Kept out of
// penumbra_study.cpp so the app's main only registers and dispatches it.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

namespace penumbra::study_app {

class ServeCommand {
 public:
  // `config_check`: the app's --config transform (a shipped config's name becomes its file).
  ServeCommand(CLI::App& app, const CLI::Validator& config_check);
  bool parsed() const { return command_->parsed(); }
  int run() const;  // serves until SIGINT or SIGTERM; throws with a one-line reason on bad options

 private:
  CLI::App* command_;
  std::filesystem::path config_, sessions_, web_, frame_cache_;
  std::string bind_ = "127.0.0.1", completion_code_, completion_url_, admin_token_;
  int port_ = 8080;
  double iti_ms_ = 400;
};

}  // namespace penumbra::study_app
