// `voxlines pack`: a .vxl to a .vxlz package (spec/vxlz-package-v2.md). The tables travel exactly; the
// vertex positions are quantised on one grid over the data's bounding cube, predicted along the
// streamlines and Draco-coded in chunks; the orders, connecting vertices and bounds are left out
// (the unpacker recomputes them, see unpack.h). The value sets travel exactly, per shipped point.
#pragma once

#include <cstdint>
#include <string>

#include "format/vxl_file.h"
#include "format/vxlz_layout.h"

namespace vxl {

struct PackSettings {
  std::uint32_t bits = kVxlzDefaultBits;  // 11..16: quantum = range / (2^bits - 1)
  unsigned threads = 0;                   // 0: all cores
  std::uint64_t chunk_points = kVxlzDefaultChunkPoints;
};

struct PackSummary {
  std::uint64_t bytes = 0;  // package size
  std::uint64_t streamlines = 0, points = 0, shipped_points = 0;
  PackSection pack{};                                             // quantisation, stated bound, measured error
  std::uint32_t point_value_sets = 0, streamline_value_sets = 0;  // carried exactly (spec §4.7)
};

// Validates the .vxl's tables as it reads them (the streamline walk) and writes `out_path` atomically.
// Throws vxl::Error: Usage for settings out of range, Input for an inconsistent .vxl, Output.
PackSummary pack_vxl(const VxlFile& file, const std::string& out_path, const PackSettings& settings);

}  // namespace vxl
