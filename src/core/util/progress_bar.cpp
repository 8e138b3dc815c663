#include "binloop/util/progress_bar.h"

#include <unistd.h>

namespace binloop {

ProgressBar::ProgressBar(std::string label, size_t total)
    : label_(std::move(label)), total_(total), tty_(isatty(fileno(stderr)) != 0) {
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(size_t done) {
  if (!tty_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double frac = total_ ? static_cast<double>(done) / total_ : 1.0;
  const int width = 30;
  const int fill = static_cast<int>(frac * width);
  const double secs = std::chrono::duration<double>(now - start_).count();
  const double eta = frac > 0 ? secs * (1 - frac) / frac : 0;
  std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu %3.0f%% %.0fs left %s ", label_.c_str(), fill,
               "##############################", width - fill, "", done, total_, 100 * frac, eta,
               status_.c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!tty_ || finished_ || total_ == 0) return;
  update(total_);
  finished_ = true;
  std::fprintf(stderr, "\n");
}

}  // namespace binloop
