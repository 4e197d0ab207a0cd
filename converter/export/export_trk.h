// Export of a .vxl to TrackVis .trk (version 2, little-endian), gzip-compressed when the name ends in
// ".gz". Points are stored in voxmm, mapped from RAS mm with the exact inverse of the affine read_trk
// applies for the header written (converter/readers/trk_header.h), so that reading the file back gives
// the streamlines to float precision.
//
// The header: a TRK source's own (dim, voxel_size, origin, vox_to_ras, voxel_order, image orientation,
// invert/swap flags, from the provenance); otherwise the TRX export's reference (export_trx.h: a TRX
// source's, or a 1 mm grid covering the bounds) with voxel_order the orientation of its vox_to_ras (RAS
// for the default). Per-point value sets become scalars and per-streamline ones properties, one name slot
// each: TRK has 10 slots of 20 bytes (Latin-1) per kind, so further sets and names it cannot hold are not
// written (a warning names them), nor are groups or streamlines without points (TRK cannot hold one).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "converter/export/streamline_subset.h"
#include "format/vxl_file.h"

namespace vxl {

struct TrkExportSummary {
  std::uint64_t streamlines = 0, points = 0;  // written
  std::vector<std::string> warnings;          // what the output cannot hold
};

// Writes `out_path` atomically (only the subset's streamlines when there is one). Throws vxl::Error:
// Unsupported when the counts or the reference's dimensions exceed TRK's integer fields, or its
// vox_to_ras is singular; Output.
TrkExportSummary export_trk(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset = nullptr);

}  // namespace vxl
