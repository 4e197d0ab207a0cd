// What the export tests share: a conversion that keeps the source's coordinates, so that an export can be
// compared with its source exactly.
#pragma once

#include <string>

#include "converter/convert/convert.h"

namespace vxl::test {

// Converts `t` to `path` with float32 positions (the source's coordinates bit for bit); returns `path`.
inline std::string convert_float32(Tractogram t, const std::string& path) {
  ConvertSettings exact;
  exact.positions = PositionEncoding::Float32;
  convert_tractogram(std::move(t), path, exact);
  return path;
}

}  // namespace vxl::test
