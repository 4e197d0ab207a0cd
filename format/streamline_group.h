// A named set of streamlines (TRX groups, spec §5.9 GRPS): what the readers fill, the writer stores and
// the reader gives back — one struct for all three.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vxl {

struct StreamlineGroup {
  std::string name;
  std::vector<std::uint64_t> members;  // streamline indices, strictly increasing
};

}  // namespace vxl
