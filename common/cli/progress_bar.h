#pragma once
// A one-line progress bar on stderr, drawn once work has run longer than half a second: "<what>
// [####....] done/total<unit>, N s left  <note>". On a terminal the line is redrawn in place at
// most ten times a second; elsewhere (a CI log, a file) a whole line is written at most every
// ten seconds and at the end, so that a log holds a few readable lines instead of one of
// thousands of carriage returns. Not thread-safe: callers serialize (fit_study does). Shared by
// penumbra-quest, penumbra-fit, penumbra-demo and penumbra-study reference.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

namespace penumbra {

class ProgressBar {
 public:
  // `unit` follows the count, e.g. " runs". `out` is stderr unless a test gives another stream.
  ProgressBar(std::string what, bool enabled, std::string unit = "", std::FILE* out = stderr)
      : what_(std::move(what)), unit_(std::move(unit)), enabled_(enabled), out_(out),
        terminal_(isatty(fileno(out)) == 1), start_(Clock::now()) {}
  ~ProgressBar() {
    if (shown_ && terminal_ && !cleared_) std::fputc('\n', out_);
  }
  // Erases the bar's line on a terminal, so that other output starts on a clean line; the bar is
  // drawn again on the next call.
  void clear() {
    if (shown_ && terminal_ && !cleared_) std::fputs("\r\033[K", out_), std::fflush(out_);
    cleared_ = true;
  }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // `note` says what is being done now (e.g. "pcf frame 120 + reference").
  void operator()(int done, int total, const std::string& note = "") {
    if (!enabled_ || total <= 0) return;
    const auto now = Clock::now();
    if (!shown_ && now - start_ < std::chrono::milliseconds(500) && done < total) return;
    const auto every = terminal_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(10000);
    if (shown_ && done < total && now - last_ < every) return;
    if (done >= total && finished_) return;
    shown_ = true;
    cleared_ = false;
    finished_ = done >= total;
    last_ = now;
    constexpr int kWidth = 40;
    const int filled = static_cast<int>(static_cast<long long>(kWidth) * std::min(done, total) / total);
    const double elapsed_s = std::chrono::duration<double>(now - start_).count();
    const double eta_s = done > 0 ? elapsed_s * (total - done) / done : 0.0;
    std::fprintf(out_, "%s%s [%s%s] %d/%d%s, %.0f s left%s%s%s", terminal_ ? "\r" : "", what_.c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(), std::string(static_cast<std::size_t>(kWidth - filled), '.').c_str(),
                 done, total, unit_.c_str(), eta_s, note.empty() ? "" : "  ", note.c_str(), terminal_ ? "\033[K" : "\n");
    std::fflush(out_);
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string what_;
  std::string unit_;
  bool enabled_;
  std::FILE* out_;
  bool terminal_;
  bool shown_ = false;
  bool finished_ = false;
  bool cleared_ = false;
  Clock::time_point start_, last_;
};

}  // namespace penumbra
