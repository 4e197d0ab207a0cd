// An image (the anatomy the viewer draws under the lines, a mask or atlas that selects streamlines) in a
// neutral form, and the reader that picks the format from the file's extension: NIfTI-1/-2 (.nii,
// .nii.gz; converter/readers/nifti_image.h) and MRtrix (.mif, .mif.gz, .mih;
// converter/readers/mrtrix_image.h). Other image formats are refused naming the format (exit 4).
//
// The checks every format's reader makes: the header's sizes against the caller's limits before any voxel
// is read (exit 4), and a sane voxel-to-RAS mapping (exit 3): finite, each voxel axis 1e-6 to 1e4 mm
// long, the origin within 1e6 mm of (0,0,0), and the axes not (nearly) coplanar.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "converter/readers/image_geometry.h"

namespace vxl {

struct VolumeImage {
  std::string path;
  std::array<std::int64_t, 3> dims{0, 0, 0};
  std::vector<float> values;              // x fastest, then y, then z
  ImageGeometry geometry;                 // as MRtrix derives it from the header (image_geometry.h)
  std::array<double, 16> voxel_to_ras{};  // row-major 4x4: voxel index (the centre of voxel (i, j, k)) -> RAS mm
};

// What a caller can hold: voxels along each axis, and voxels in all (of the first volume). The reader
// refuses a larger image from its header, before reading (and inflating) anything.
struct ImageLimits {
  std::int64_t max_axis = std::int64_t(1) << 31;
  std::uint64_t max_voxels = std::uint64_t(1) << 30;
  std::string reason = "at most 2^30 voxels are read";  // completes the refusal: why this limit
};

// Makes room for an image's `voxels` float32 samples before any is read. Throws vxl::Error (Unsupported, naming
// `path`, the bytes and what bounds this process's memory) when they cannot be allocated.
void reserve_values(VolumeImage& image, const std::string& path, std::uint64_t voxels);

// Reads `path` as the format its extension names (case-insensitive). Throws vxl::Error: Input (exit 3)
// for a malformed file, Unsupported (exit 4) for another format, a feature or a size beyond `limits`.
VolumeImage read_volume_image(const std::string& path, const ImageLimits& limits = {});

// Whether `path` names an image format (read or refused with a message), by its extension.
bool is_image_name(const std::string& path);

// For the formats' readers: refuses (exit 4) dims beyond `limits`, naming `path` and the format.
void check_image_size(const std::string& path, const std::array<std::int64_t, 3>& dims, const ImageLimits& limits);

// For the formats' readers: refuses (exit 3) an absurd voxel-to-RAS mapping (see above); `source`
// names it in the message ("the sform", "the transform").
void check_voxel_to_ras(const std::string& path, const std::array<double, 16>& voxel_to_ras, const std::string& source);

}  // namespace vxl
