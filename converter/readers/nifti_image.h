// Reads an image (NIfTI-1 or NIfTI-2, .nii or .nii.gz) with Debian's nifti_clib (libnifti2): the anatomy
// the viewer draws under the lines, and the masks and atlases that select streamlines. Every malformed
// file is a vxl::Error naming it (exit 3); sizes beyond what we handle are exit 4. The header's size,
// magic and dimensions are checked against the file, and the voxels read, here; nifti_clib interprets
// the header (types, byte order, transforms). Single-file NIfTI only (.hdr/.img pairs are refused, exit 4).
//
//   values  any NIfTI data type, as float, scaled by scl_slope / scl_inter (slope 0: unscaled); RGB and
//           complex types give their mean / magnitude; NaN and infinities become 0. A 4D image gives its
//           first volume.
//   space   the sform when sform_code > 0, else the qform (the library's pixel-size matrix when neither is
//           set), in mm (metre and micron units converted): voxel index -> RAS mm.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vxl {

struct NiftiImage {
  std::string path;
  std::array<std::int64_t, 3> dims{0, 0, 0};
  std::vector<float> values;              // x fastest, then y, then z
  std::array<double, 16> voxel_to_ras{};  // row-major 4x4: voxel index (the centre of voxel (i, j, k)) -> RAS mm
};

NiftiImage read_nifti_image(const std::string& path);

}  // namespace vxl
