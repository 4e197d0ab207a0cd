// Reads an MRtrix image (.mif, .mif.gz, or a .mih header naming its data file) into a VolumeImage. The
// header (converter/readers/mrtrix_header.h) gives:
//   dim        the sizes, x first (missing axes count 1; axes past the third are read at index 0)
//   vox        the voxel sizes in mm
//   layout     the order and direction in which the data are stored: "+0,+1,+2" is x fastest; "-0" stores
//              axis 0 from its last index to its first. The voxel-to-scanner mapping does not depend on it.
//   datatype   Int8, UInt8, (U)Int16/32/64, Float32/64, CFloat32/64 (their magnitude), each with LE or BE
//              for the byte order (none: little-endian); Bit is refused (exit 4)
//   transform  three rows of four numbers: scanner (RAS mm) = R * (vox * index) + t (identity when absent)
//   scaling    optional "offset,multiplier": value = offset + multiplier * stored
//   file       ". OFFSET" (this file) or, in a .mih, "NAME [OFFSET]" beside it; data in several files is
//              refused (exit 4)
// A .mif.gz is inflated through converter/readers/image_file.h as a .nii.gz is, and the sizes are checked against the
// caller's ImageLimits before any voxel is read.
#pragma once

#include <string>

#include "converter/readers/volume_image.h"

namespace vxl {

VolumeImage read_mrtrix_image(const std::string& path, const ImageLimits& limits = {});

}  // namespace vxl
