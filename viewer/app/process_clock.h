// When this process started, on the steady clock: what --stats counts its times from, so that they include
// loading the program and its libraries, as a user waiting for the window does.
#pragma once

#include <chrono>

namespace vxl::app {

std::chrono::steady_clock::time_point process_start();
// The seconds from the process start to the program's static initialisation, just before main: what loading
// the program and its shared libraries took (0 where /proc cannot tell).
double seconds_before_main();
// The seconds from the process start to now.
double seconds_since_process_start();

}  // namespace vxl::app
