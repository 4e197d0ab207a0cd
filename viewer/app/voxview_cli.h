// voxview's command-line schema (CLI11): its options, their checks and help, bound to a ViewerArguments.
// What the options mean together is decided later, by resolve_viewer_options (viewer_arguments.h).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "viewer/app/viewer_arguments.h"

namespace vxl::app {

// The help's description: what voxview does, then its mouse gestures and keys (key_bindings.h).
std::string voxview_description(const std::string& version);

// Declares voxview's options on `cli`, bound to `arguments`.
void declare_voxview_options(CLI::App& cli, ViewerArguments& arguments);

// Parses argv into the arguments `cli` was declared with and notes which options were given. Throws
// CLI::ParseError (CLI::CallForHelp for --help).
void parse_voxview_command_line(CLI::App& cli, ViewerArguments& arguments, int argc, const char* const* argv);

}  // namespace vxl::app
