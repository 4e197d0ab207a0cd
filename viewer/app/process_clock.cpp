#include "viewer/app/process_clock.h"

#include <chrono>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

namespace vxl::app {

namespace {

// The seconds since the kernel started this process (/proc/self/stat's starttime, in clock ticks since boot,
// against CLOCK_BOOTTIME); 0 where /proc cannot tell.
double seconds_since_exec() {
  std::ifstream stat("/proc/self/stat");
  std::string text;
  std::getline(stat, text);
  // The command name (field 2) may hold spaces and parentheses: fields are counted after its last ')'.
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  unsigned long long start_ticks = 0;
  for (int n = 3; n <= 22 && fields >> field; ++n)
    if (n == 22) start_ticks = std::stoull(field);
  timespec now{};
  const long ticks_per_s = sysconf(_SC_CLK_TCK);
  if (start_ticks == 0 || ticks_per_s <= 0 || clock_gettime(CLOCK_BOOTTIME, &now) != 0) return 0;
  const double elapsed = double(now.tv_sec) + now.tv_nsec * 1e-9 - double(start_ticks) / double(ticks_per_s);
  return elapsed > 0 && elapsed < 60 ? elapsed : 0;  // a clock that disagrees: count from here instead
}

// Taken during static initialisation, before main: what the dynamic loader spent is added from /proc.
const double g_before_main = seconds_since_exec();
const std::chrono::steady_clock::time_point g_start =
    std::chrono::steady_clock::now() -
    std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(g_before_main));

}  // namespace

double seconds_before_main() { return g_before_main; }
double seconds_since_process_start() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - g_start).count();
}

}  // namespace vxl::app
