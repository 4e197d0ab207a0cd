// Export of a .vxl back to the source streamlines, as a TCK file (Float32LE, RAS mm), and optionally one
// per-point value set beside it as an MRtrix TSF (track scalar file).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

struct TckExportSettings {
  std::optional<std::string> tsf_path;  // write a per-point value set here
  std::optional<std::string> value;     // the set to write (default: the first)
  std::optional<std::string> group;     // only this group's streamlines (not with a subset)
};

struct ExportSummary {
  std::uint64_t streamlines = 0, points = 0;
  std::string value_set;              // the set written to the TSF, if any
  std::vector<std::string> warnings;  // values the output cannot hold (the caller decides how to show them)
};

// Writes `out_path` (and the TSF) atomically; the streamlines are those the converter read (spec §5.6),
// bit-exact for float32 sources, and the TSF holds the source points' values bit-exact; only the
// subset's (or the group's) streamlines when there is one. Groups not written are a warning. Both headers
// carry a source TCK header's properties as tckedit does (export_tck.cpp says which), then the `header`
// lines, whose keys replace the source's. Throws vxl::Error: Usage when a TSF is asked for and the file
// has no per-point values or none named `value`, when the TSF and the TCK are one file (by any name),
// when `group` names no group of the file; Unsupported when a value is NaN or infinite (TSF separators);
// Output.
ExportSummary export_tck(const VxlFile& file, const std::string& out_path, const TckExportSettings& settings = {},
                         const StreamlineSubset* subset = nullptr, const std::vector<std::string>& header = {});

}  // namespace vxl
