#pragma once
// `penumbra-study reference`: the reference filter size (stimuli/reference.h) for every pattern,
// contrast and artifact size asked for, written as one JSON file that `penumbra-fit --reference`
// reads. Kept out of penumbra_study.cpp so the app's main only registers and dispatches it.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "stimuli/reference.h"

namespace penumbra::study_app {

class ReferenceCommand {
 public:
  explicit ReferenceCommand(CLI::App& app);
  bool parsed() const { return command_->parsed(); }
  int run() const;  // throws with a one-line reason on bad options

 private:
  CLI::App* command_;
  std::vector<std::string> patterns_ = {"stair", "step"};
  std::vector<double> contrasts_ = {1.0, 0.5};
  std::vector<double> artifact_px_ = {5, 10, 20};
  std::string kernel_ = "disk", transfer_ = "srgb", partner_ = "original";
  int size_px_ = 320;
  int poisson_taps_ = 32;
  stimuli::ReferenceSearch search_;
  std::filesystem::path output_;
  bool no_progress_ = false;
};

}  // namespace penumbra::study_app
