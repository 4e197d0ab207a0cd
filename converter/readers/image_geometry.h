// Where an image's voxels lie, as MRtrix derives it from a header, so that a mask selects exactly what tckedit
// selects and the viewer shows an image where mrview does. MRtrix keeps a transform whose three axes are unit
// vectors and the voxel sizes apart:
//   * NIfTI with an sform: the sform's columns normalised; the sizes are pixdim (its magnitude), or the columns'
//     lengths when pixdim differs from one of them by more than a relative 1e-5;
//   * NIfTI with a qform only: the quaternion (b, c, d; a = sqrt(1 - b² - c² - d²), the vector normalised
//     instead when that is below 1e-7), the third axis negated when pixdim[0] < 0, the sizes pixdim;
//   * NIfTI with neither (both codes 0), or an MRtrix image without 'transform:': no rotation, the sizes pixdim
//     (or 'vox:'), the image centred on the origin (its centre voxel's centre at (0, 0, 0));
//   * an MRtrix image: 'transform:' and 'vox:', the axes normalised (and the sizes scaled by their lengths) when
//     one is not of unit length to 1e-6.
// NIfTI's xyzt_units are ignored, as MRtrix ignores them. Arithmetic is Eigen's in double, as MRtrix's is.
//
// A mask is then tested in MRtrix's realigned image: its axes permuted and flipped to the nearest of
// (+x, +y, +z) (Header::realign_transform), cropped to the set voxels and one more on each side (tckedit's
// Mask), and a point p is in voxel round(S p), S the cropped image's scanner-to-voxel affine rounded to float32
// and applied in float32, std::round taking halves away from zero. A point on a face between two voxels of a
// flipped axis thus goes to the one it would not go to in the stored order; the crop moves the origin, which
// changes the float32 rounding of an oblique image's lookup.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace vxl {

struct ImageGeometry {
  std::array<double, 12> transform{};  // row-major 3x4: unit axis directions (columns 0-2), origin (column 3), mm
  std::array<double, 3> spacing{};     // voxel sizes along the three axes, mm
  // voxel index (the centre of voxel (i, j, k)) -> RAS mm: the transform with its axes scaled by the sizes.
  std::array<double, 16> voxel_to_ras() const;
};

// The NIfTI header's fields that MRtrix reads for the geometry (float fields widened to double).
struct NiftiGeometryFields {
  int sform_code = 0, qform_code = 0;
  std::array<std::array<double, 4>, 3> srow{};  // srow_x, srow_y, srow_z
  double quatern_b = 0, quatern_c = 0, quatern_d = 0;
  std::array<double, 3> qoffset{};
  std::array<double, 4> pixdim{};  // pixdim[0] (qfac) to pixdim[3]
};
ImageGeometry nifti_geometry(const NiftiGeometryFields& fields, const std::array<std::int64_t, 3>& dims);

// An MRtrix header's 'transform:' (3 rows of 4; none: the default, centred geometry) and 'vox:' sizes.
ImageGeometry mrtrix_geometry(const std::optional<std::array<double, 12>>& transform, const std::array<double, 3>& vox,
                              const std::array<std::int64_t, 3>& dims);

// How a mask is looked up as tckedit looks it up (see above): in the realigned image cropped, as tckedit crops
// it, to the set voxels (their bounds first..last in the stored order) and one voxel more on each side.
struct MaskLookup {
  std::array<float, 12> scanner_to_voxel{};  // row-major 3x4, float32: the cropped realigned image's
  std::array<std::int64_t, 3> dims{};        // the cropped realigned image's sizes
  // The sample a cropped realigned index (n0, n1, n2) stands for: offset + n0 step[0] + n1 step[1] + n2 step[2]
  // in the stored order (x fastest, then y, then z).
  std::int64_t offset = 0;
  std::array<std::int64_t, 3> step{};
};
MaskLookup mask_lookup(const ImageGeometry& geometry, const std::array<std::int64_t, 3>& dims,
                       const std::array<std::int64_t, 3>& first, const std::array<std::int64_t, 3>& last);

}  // namespace vxl
