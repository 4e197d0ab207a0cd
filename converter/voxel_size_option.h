// --voxel-size as `voxlines convert` and voxview take it: a positive number of mm, or auto (voxel_size_auto.h).
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace vxl {

struct VoxelSizeArgument {
  double mm = 10.0;        // the size given (or the default)
  bool automatic = false;  // auto: chosen from the data
};

// Adds --voxel-size MM|auto to `command`, read into `text` (default 10), with `help` and a check whose message says
// what is expected.
CLI::Option* add_voxel_size_option(CLI::App& command, std::string& text, const std::string& help);

// What a --voxel-size that passed the check says.
VoxelSizeArgument parse_voxel_size(const std::string& text);

}  // namespace vxl
