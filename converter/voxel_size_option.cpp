#include "converter/voxel_size_option.h"

#include <cmath>
#include <cstdlib>

namespace vxl {

CLI::Option* add_voxel_size_option(CLI::App& command, std::string& text, const std::string& help) {
  return command.add_option("--voxel-size", text, help)
      ->type_name("MM|auto")
      ->default_val("10")
      ->check([](const std::string& given) -> std::string {
        if (given == "auto") return {};
        char* end = nullptr;
        const double v = std::strtod(given.c_str(), &end);
        if (end == given.c_str() || *end != '\0' || !(v > 0) || !std::isfinite(v))
          return "expected a positive number of mm or auto, got '" + given + "'";
        return {};
      });
}

VoxelSizeArgument parse_voxel_size(const std::string& text) {
  if (text == "auto") return {10.0, true};
  return {std::strtod(text.c_str(), nullptr), false};
}

}  // namespace vxl
