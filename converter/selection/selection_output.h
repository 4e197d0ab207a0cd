// Writes the streamlines a selection kept (a StreamlineSubset of a .vxl) to a new file, in source order,
// the format chosen by the output's extension:
//   .tck  positions (and, with a TSF path, one per-point value set beside it);
//   .trx  positions, groups (their members among the kept streamlines), dpv and dps;
//   .vtk  legacy POLYDATA with the value sets;
//   .vxl  converted again with the input's voxel size, orders, position encoding and levels, its
//         provenance the input's source (packed positions are packed again from their decoded values,
//         within twice the packed bound of the source's).
// An empty subset writes a valid empty file. Every output is written atomically.
#pragma once

#include <string>
#include <vector>

#include "converter/export/export_tck.h"
#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// True for the extensions above (case-insensitive).
bool is_selection_output(const std::string& path);

// `header`: lines for a TCK's header (e.g. the selection's criteria). Returns warnings (values or groups
// the output cannot hold). Throws vxl::Error.
std::vector<std::string> write_selection(const VxlFile& file, const StreamlineSubset& subset,
                                         const std::string& out_path, const TckExportSettings& tck,
                                         const std::vector<std::string>& header);

}  // namespace vxl
