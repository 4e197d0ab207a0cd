// `voxlines info` of a .vxlz package (spec/vxlz-package-v2.md): what it holds and how it was packed, from its tables
// alone once open() has checked them and every checksum (no position is decoded).
#pragma once

#include <nlohmann/json.hpp>

#include "format/vxlz_package.h"

namespace vxl::cli {

// The summary as JSON (`info --json`): counts, grid, quantisation and its error bound, the shipping order with each
// level's prefix (§5.1), the chunks, the sections and the source.
nlohmann::json package_info(const VxlzFile& package);

// The same as text, one line a topic.
void print_package_info(const nlohmann::json& info);

}  // namespace vxl::cli
