#include "converter/cli/progress_bar.h"

#include <cstdio>

#include <unistd.h>

namespace vxl::cli {

bool ProgressBar::stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(std::string label)
    : enabled_(stderr_is_terminal()), label_(std::move(label)), start_(std::chrono::steady_clock::now()) {
  if (!label_.empty()) label_ += "  ";
}
ProgressBar::~ProgressBar() { done(); }

void ProgressBar::update(const char* stage, double fraction) {
  if (!enabled_) return;
  int percent = static_cast<int>(fraction * 100.0 + 0.5);
  if (stage_ == stage && percent == last_percent_) return;
  stage_ = stage;
  last_percent_ = percent;
  const int width = 30;
  int filled = percent * width / 100;
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r%s%-12s [%.*s%*s] %3d%%  %.1fs", label_.c_str(), stage, filled,
               "##############################", width - filled, "", percent, seconds);
  std::fflush(stderr);
}

void ProgressBar::done() {
  if (enabled_ && last_percent_ >= 0) std::fprintf(stderr, "\r%*s\r", 70 + static_cast<int>(label_.size()), "");
  last_percent_ = -1;
}

}  // namespace vxl::cli
