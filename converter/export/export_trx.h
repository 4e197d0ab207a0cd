// Export of a .vxl back to TRX (https://github.com/tee-ar-ex/trx-spec), so that a converted tractogram
// goes back into the community's tools: a zip archive, every member stored (not compressed), with
//
//   header.json          DIMENSIONS, VOXEL_TO_RASMM, NB_STREAMLINES, NB_VERTICES
//   positions.3.float32  the source points, RAS mm (synthetic face points dropped), bit-exact
//   offsets.uint64       NB_STREAMLINES + 1 entries: each streamline's first point, then NB_VERTICES
//   groups/NAME.uint32   the members of every group of the .vxl's GRPS section
//   dpv/NAME.float32     every per-point value set (VVAL) at the source points (export_values.h)
//   dps/NAME.float32     every per-streamline value set (SVAL); NAME[0..m-1] sets as one NAME.m.float32
//   dpg/GROUP/NAME[.n].DTYPE  every row of values per group (GDAT), its bytes and dtype as the source had them
//
// DIMENSIONS and VOXEL_TO_RASMM describe the reference image. They come from the provenance when the
// source had them (a TRX header.json; a TRK header's dim and vox_to_ras); otherwise (TCK, synthetic)
// the reference is a 1 mm grid whose voxel (0, 0, 0) is centred on floor(bounds_min) and which covers
// the bounds: VOXEL_TO_RASMM = [[1,0,0,fx],[0,1,0,fy],[0,0,1,fz],[0,0,0,1]], DIMENSIONS =
// ceil(bounds_max - floor(bounds_min)) + 1 (1 x 1 x 1 and the identity without points).
#pragma once

#include <array>
#include <string>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

// The reference image written to header.json.
struct TrxReference {
  std::array<std::int64_t, 3> dimensions{1, 1, 1};
  std::array<std::array<double, 4>, 4> voxel_to_rasmm{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
};

// From the provenance when it records one, else the default above.
TrxReference trx_reference(const VxlFile& file);

// Writes `out_path` (the archive appears only when complete). Throws vxl::Error: Input for a malformed
// file, Unsupported for a group or value set name that cannot be a member name (or is another group's too)
// or more than 2^32 - 1 streamlines (group members are uint32), both before the archive is created;
// Output only when the archive cannot be written.
// With a subset, only its streamlines (and their values; groups keep their members among them).
void export_trx(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset = nullptr);

}  // namespace vxl
