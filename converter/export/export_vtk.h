// Export of a .vxl to legacy VTK: BINARY (big-endian, as VTK writes it) POLYDATA, one LINES cell per
// streamline; per-vertex value sets as POINT_DATA SCALARS, per-streamline ones as CELL_DATA SCALARS, and
// each group as a CELL_DATA unsigned_char array named after it (1: member, 0: not), which the readers
// (ours included) take as a per-streamline value set.
#pragma once

#include <string>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// Writes `out_path` atomically; the points are those the converter read (spec §5.6), bit-exact for float32
// sources, and the values those of the source points (synthetic face points dropped). Throws vxl::Error
// (Unsupported when the tractogram is beyond the 32-bit indices of legacy LINES).
// With a subset, only its streamlines and their values.
void export_vtk(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset = nullptr);

}  // namespace vxl
