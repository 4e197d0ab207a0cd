// The neutral in-memory tractogram every source reader fills and every later stage consumes.
//
// Coordinate convention: RAS millimetres (world space of TCK/TRX; TRK readers map voxmm to RAS).
// Positions are float32 because every stage after reading (voxel assignment, the .vxl file, export)
// works on exactly these values: a float32 source round-trips bit-exactly.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "format/streamline_group.h"
#include "format/vxl_group_values.h"

namespace vxl {

// What the readers know of the source file, kept as provenance in the .vxl.
struct SourceInfo {
  std::string path;                                  // as given by the user
  std::string format;                                // "tck", "trk", "trx"
  std::string dtype;                                 // coordinate type in the source, e.g. "Float32LE", "float16"
  std::uint64_t bytes = 0;                           // size of the source (sum of member files for a TRX directory)
  std::string xxh3_128;                              // 32 hex digits (see spec §5.8)
  nlohmann::json header;                             // the source header as JSON
  std::optional<std::array<double, 16>> vox_to_ras;  // row-major 4x4, when the source has one
  std::vector<std::string> warnings;                 // non-fatal problems found while reading
  // Files that added values (TSF): {"name", "bytes", "xxh3_128", "header"} each, for provenance.
  nlohmann::json value_files = nlohmann::json::array();
};

// Values a source carries besides positions (a TSF file, TRK scalars and properties, TRX dpv and dps),
// kept so that the viewer can colour by them.
struct ValueSet {
  std::string name;
  std::vector<float> values;
};

struct Tractogram {
  std::vector<float> positions;             // x,y,z interleaved, 3 * point_count() floats
  std::vector<std::uint64_t> offsets;       // streamline i = points [offsets[i], offsets[i+1]); size N+1
  std::vector<StreamlineGroup> groups;      // TRX groups, when the source has them
  std::vector<GroupValues> group_values;    // TRX dpg: one row per (group, name), in the source's dtype
  std::vector<ValueSet> point_values;       // each point_count() values, in point order
  std::vector<ValueSet> streamline_values;  // each streamline_count() values
  SourceInfo source;

  Tractogram() : offsets{0} {}
  std::uint64_t streamline_count() const { return offsets.size() - 1; }
  std::uint64_t point_count() const { return positions.size() / 3; }

  // Appends one streamline of n points (xyz interleaved).
  void add_streamline(const float* xyz, std::size_t n) {
    positions.insert(positions.end(), xyz, xyz + 3 * n);
    offsets.push_back(point_count());
  }
};

}  // namespace vxl
