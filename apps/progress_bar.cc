#include "apps/progress_bar.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace catgraph {

ProgressBar::ProgressBar(std::string unit)
    : unit_(std::move(unit)), start_(std::chrono::steady_clock::now()), tty_(::isatty(STDERR_FILENO) != 0) {}

void ProgressBar::Update(std::size_t done, std::size_t total) {
  Update(done, total, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
}

void ProgressBar::Update(std::size_t done, std::size_t total, double elapsed_s) {
  if (total == 0) return;
  const double fraction = static_cast<double>(done) / static_cast<double>(total);
  const double eta = done > 0 ? elapsed_s / static_cast<double>(done) * static_cast<double>(total - done) : 0.0;
  const std::size_t decile = static_cast<std::size_t>(fraction * 10.0);
  if (!tty_ && decile == last_decile_ && done != total) return;
  last_decile_ = decile;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  std::fprintf(stderr, "%s[%s%s] %zu/%zu %s, %s elapsed, ETA %s%s", tty_ ? "\r" : "",
               std::string(static_cast<std::size_t>(filled), '#').c_str(),
               std::string(static_cast<std::size_t>(kWidth - filled), ' ').c_str(), done, total,
               unit_.c_str(), FormatDuration(elapsed_s).c_str(), FormatDuration(eta).c_str(),
               tty_ && done != total ? "" : "\n");
  std::fflush(stderr);
}

std::string FormatDuration(double seconds) {
  char buffer[32];
  const long t = std::lround(seconds);
  if (t >= 3600) std::snprintf(buffer, sizeof buffer, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else std::snprintf(buffer, sizeof buffer, "%ldm%02lds", t / 60, t % 60);
  return buffer;
}

}  // namespace catgraph
