// A progress bar on standard error for long commands (sweep, simulate):
// redrawn in place on a terminal, one line per tenth on a pipe or a log, so
// that CI logs stay short.
#ifndef CATGRAPH_APPS_PROGRESS_BAR_H_
#define CATGRAPH_APPS_PROGRESS_BAR_H_

#include <chrono>
#include <cstddef>
#include <string>

namespace catgraph {

class ProgressBar {
 public:
  // `unit` names what is counted ("runs", "frames").
  explicit ProgressBar(std::string unit);

  // `done` of `total` finished; the elapsed time is measured from
  // construction unless given.
  void Update(std::size_t done, std::size_t total);
  void Update(std::size_t done, std::size_t total, double elapsed_s);

 private:
  std::string unit_;
  std::chrono::steady_clock::time_point start_;
  std::size_t last_decile_ = 0;
  bool tty_;
};

// "1m05s" or "2h03m".
std::string FormatDuration(double seconds);

}  // namespace catgraph

#endif  // CATGRAPH_APPS_PROGRESS_BAR_H_
