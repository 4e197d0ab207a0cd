// Times since this process started: what --stats counts from, so that they include loading the program and its
// libraries, as a user waiting for the window does.
#pragma once

namespace vxl::app {

// The seconds from the process start to the program's static initialisation, just before main: what loading
// the program and its shared libraries took (0 where /proc cannot tell).
double seconds_before_main();
// The seconds from the process start to now.
double seconds_since_process_start();

}  // namespace vxl::app
