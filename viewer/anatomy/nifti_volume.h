// Reads an anatomical image (NIfTI-1 or NIfTI-2, .nii or .nii.gz) into a render-side Volume, with
// Debian's nifti_clib (libnifti2). Every malformed file is a vxl::Error naming it (exit 3); sizes beyond
// what the viewer handles are exit 4. The header's size, magic and dimensions are checked against the
// file, and the voxels read, here; nifti_clib interprets the header (types, byte order, transforms).
// Single-file NIfTI only (.hdr/.img pairs are refused, exit 4).
//
//   values  any NIfTI data type, as float, scaled by scl_slope / scl_inter (slope 0: unscaled); RGB and
//           complex types give their mean / magnitude; NaN and infinities become 0. A 4D image gives its
//           first volume.
//   space   the sform when sform_code > 0, else the qform (the library's pixel-size matrix when neither is
//           set), in mm (metre and micron units converted): voxel index -> RAS mm.
//   window  the default grey range: the 2nd and 98th percentiles of the image's non-zero voxels (the air
//           around a head is 0 in most T1s and would otherwise pull the window down); of all voxels
//           when every one is 0.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "viewer/render/volume.h"

namespace vxl {

Volume read_nifti_volume(const std::string& path);

// The p-th percentile (0..100, nearest rank) of `values`' non-zero finite entries (of all finite ones
// when none is non-zero); {0, 1} when there is none.
std::array<float, 2> percentile_window(const std::vector<float>& values, double low_percent, double high_percent);

}  // namespace vxl
