#pragma once
// A one-line progress bar on stderr, drawn once work has run longer than half a second and at
// most ten times a second: "<what> [####....] done/total<unit>, N s left". Not thread-safe:
// callers serialize (fit_study does). Shared by penumbra-quest and penumbra-fit.
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

namespace penumbra {

class ProgressBar {
 public:
  // `unit` follows the count, e.g. " runs".
  ProgressBar(std::string what, bool enabled, std::string unit = "")
      : what_(std::move(what)), unit_(std::move(unit)), enabled_(enabled), start_(Clock::now()) {}
  ~ProgressBar() {
    if (shown_) std::fputc('\n', stderr);
  }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void operator()(int done, int total) {
    if (!enabled_ || total <= 0) return;
    const auto now = Clock::now();
    if (!shown_ && now - start_ < std::chrono::milliseconds(500)) return;
    if (shown_ && done < total && now - last_ < std::chrono::milliseconds(100)) return;
    shown_ = true;
    last_ = now;
    constexpr int kWidth = 40;
    const int filled = static_cast<int>(static_cast<long long>(kWidth) * done / total);
    const double elapsed_s = std::chrono::duration<double>(now - start_).count();
    const double eta_s = done > 0 ? elapsed_s * (total - done) / done : 0.0;
    std::fprintf(stderr, "\r%s [%s%s] %d/%d%s, %.0f s left ", what_.c_str(), std::string(filled, '#').c_str(),
                 std::string(kWidth - filled, '.').c_str(), done, total, unit_.c_str(), eta_s);
    std::fflush(stderr);
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string what_;
  std::string unit_;
  bool enabled_;
  bool shown_ = false;
  Clock::time_point start_, last_;
};

}  // namespace penumbra
