#pragma once
// A one-line progress bar for command-line tools. Draws on stderr only when stderr is a terminal,
// so logs and CI output stay clean.
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>

namespace binloop {

/// Progress of a long computation: (done, total). A ProgressBar's update fits it.
using ProgressFn = std::function<void(size_t, size_t)>;

class ProgressBar {
 public:
  /// `total` may be left 0 and given with update(done, total), for callbacks that learn it late.
  explicit ProgressBar(std::string label, size_t total = 0);
  ~ProgressBar();  // finishes the line if it was drawn
  void update(size_t done);
  void update(size_t done, size_t total) {
    total_ = total;
    update(done);
  }
  void finish();
  /// Text drawn after the bar (e.g. a rate and a state); kept until changed.
  void setStatus(std::string status) { status_ = std::move(status); }

 private:
  std::string label_, status_;
  size_t total_;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace binloop
