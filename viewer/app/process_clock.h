// When this process started, on the steady clock: what --stats counts its times from, so that they include
// loading the program and its libraries, as a user waiting for the window does.
#pragma once

#include <chrono>

namespace vxl::app {

std::chrono::steady_clock::time_point process_start();

}  // namespace vxl::app
