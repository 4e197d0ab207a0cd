// Reads a NIfTI-1 or NIfTI-2 image (.nii, or .nii.gz by its gzip magic) into a VolumeImage; nifti_clib
// (Debian's libnifti2) interprets the header (types, byte order, transforms), and the voxels are read here
// a block at a time through converter/readers/image_file.h (the .trk.gz rules: a damaged, truncated or
// trailing-junk gzip stream is exit 3). Single-file NIfTI only (.hdr/.img pairs are refused, exit 4).
//
//   limits  the header's dimensions against the caller's ImageLimits, and a .nii.gz's claimed size
//           against its inflate cap (ImageFile::check_claim), before any voxel is read (exit 4).
//   values  any NIfTI data type but BINARY and COMPLEX256 (exit 4), as float, scaled by scl_slope /
//           scl_inter (slope 0: unscaled); RGB and complex types give their mean / magnitude; NaN and
//           infinities become 0. A 4D image gives its first volume.
//   space   the sform when sform_code > 0, else the qform (the library's pixel-size matrix when neither is
//           set), in mm (metre and micron units converted): voxel index -> RAS mm, checked sane
//           (check_voxel_to_ras).
#pragma once

#include <string>

#include "converter/readers/volume_image.h"

namespace vxl {

VolumeImage read_nifti_image(const std::string& path, const ImageLimits& limits = {});

}  // namespace vxl
