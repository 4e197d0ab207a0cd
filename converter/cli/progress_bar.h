// A one-line progress bar on stderr, drawn only when stderr is a terminal (quiet in pipes and CI).
#pragma once

#include <chrono>
#include <string>

namespace vxl::cli {

class ProgressBar {
 public:
  // `label` is drawn before the stage (the cohort form names the file there); empty: nothing.
  explicit ProgressBar(std::string label = {});
  ~ProgressBar();
  void update(const char* stage, double fraction);  // thread-compatible: called from one thread
  void done();

  static bool stderr_is_terminal();

 private:
  bool enabled_;
  std::string label_;
  std::string stage_;
  int last_percent_ = -1;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace vxl::cli
