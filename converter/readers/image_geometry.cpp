#include "converter/readers/image_geometry.h"

#include <cmath>
#include <cstdlib>

#include <Eigen/Geometry>

namespace vxl {
namespace {

using Affine = Eigen::Transform<double, 3, Eigen::AffineCompact>;

Affine to_affine(const std::array<double, 12>& m) {
  Affine t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) t.matrix()(r, c) = m[std::size_t(4 * r + c)];
  return t;
}

std::array<double, 12> to_array(const Affine& t) {
  std::array<double, 12> m{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m[std::size_t(4 * r + c)] = t.matrix()(r, c);
  return m;
}

// No rotation, the image centred on the origin: what MRtrix gives an image without a transform.
Affine centred(const std::array<double, 3>& spacing, const std::array<std::int64_t, 3>& dims) {
  Affine t;
  t.setIdentity();
  for (int a = 0; a < 3; ++a) t.translation()[a] = -0.5 * double(dims[std::size_t(a)] - 1) * spacing[std::size_t(a)];
  return t;
}

// MRtrix's last word on a transform (Header::sanitise_transform): a non-finite one is replaced by the centred
// one; axes not of unit length (to 1e-6) are normalised and the sizes scaled by their lengths.
ImageGeometry sanitised(Affine t, std::array<double, 3> spacing, const std::array<std::int64_t, 3>& dims) {
  if (!t.matrix().allFinite()) t = centred(spacing, dims);
  bool rescale = false;
  for (int a = 0; a < 3; ++a) rescale |= std::abs(t.matrix().col(a).head<3>().norm() - 1.0) > 1.0e-6;
  if (rescale)
    for (int a = 0; a < 3; ++a) {
      const double length = t.matrix().col(a).head<3>().norm();
      t.matrix().col(a).head<3>() /= length;
      spacing[std::size_t(a)] *= length;
    }
  return ImageGeometry{to_array(t), spacing};
}

}  // namespace

std::array<double, 16> ImageGeometry::voxel_to_ras() const {
  const Affine v = to_affine(transform) * Eigen::DiagonalMatrix<double, 3>(spacing[0], spacing[1], spacing[2]);
  std::array<double, 16> m{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m[std::size_t(4 * r + c)] = v.matrix()(r, c);
  m[15] = 1.0;
  return m;
}

ImageGeometry nifti_geometry(const NiftiGeometryFields& f, const std::array<std::int64_t, 3>& dims) {
  std::array<double, 3> pixdim{};
  for (int a = 0; a < 3; ++a) pixdim[std::size_t(a)] = std::abs(f.pixdim[std::size_t(a + 1)]);
  std::array<double, 3> spacing = pixdim;
  Affine t;
  t.matrix().setConstant(std::numeric_limits<double>::quiet_NaN());  // neither form: the centred geometry
  if (f.sform_code != 0) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) t.matrix()(r, c) = f.srow[std::size_t(r)][std::size_t(c)];
    bool rescale = false;
    for (int a = 0; a < 3 && !rescale; ++a)
      rescale = std::abs(pixdim[std::size_t(a)] / t.matrix().col(a).head<3>().norm() - 1.0) > 1e-5;
    for (int a = 0; a < 3; ++a) {
      const double length = t.matrix().col(a).head<3>().norm();
      t.matrix().col(a).head<3>() /= length;
      spacing[std::size_t(a)] = rescale ? length : pixdim[std::size_t(a)];
    }
  } else if (f.qform_code != 0) {
    Eigen::Quaterniond q(0.0, f.quatern_b, f.quatern_c, f.quatern_d);
    const double w = 1.0 - q.squaredNorm();
    if (w < 1.0e-7)
      q.normalize();
    else
      q.w() = std::sqrt(w);
    t.matrix().topLeftCorner<3, 3>() = q.matrix();
    for (int a = 0; a < 3; ++a) t.translation()[a] = f.qoffset[std::size_t(a)];
    if (f.pixdim[0] < 0.0) t.matrix().col(2) *= -1.0;
  }
  return sanitised(t, spacing, dims);
}

ImageGeometry mrtrix_geometry(const std::optional<std::array<double, 12>>& transform, const std::array<double, 3>& vox,
                              const std::array<std::int64_t, 3>& dims) {
  Affine t;
  t.matrix().setConstant(std::numeric_limits<double>::quiet_NaN());
  if (transform) t = to_affine(*transform);
  return sanitised(t, vox, dims);
}

MaskLookup mask_lookup(const ImageGeometry& g, const std::array<std::int64_t, 3>& dims,
                       const std::array<std::int64_t, 3>& first, const std::array<std::int64_t, 3>& last) {
  // The permutation and flips to the nearest of (+x, +y, +z) (MRtrix's Axes::get_permutation_to_make_axial):
  // each scanner axis takes the image axis with the largest component along it, a taken axis the one left.
  Affine m = to_affine(g.transform);
  std::array<int, 3> perm{};
  for (int r = 0; r < 3; ++r) m.matrix().topLeftCorner<3, 3>().row(r).cwiseAbs().maxCoeff(&perm[std::size_t(r)]);
  auto other = [](int a, int b) { return a != 0 && b != 0 ? 0 : a != 1 && b != 1 ? 1 : 2; };
  if (perm[0] == perm[1]) perm[1] = other(perm[0], perm[2]);
  if (perm[0] == perm[2]) perm[2] = other(perm[0], perm[1]);
  if (perm[1] == perm[2]) perm[2] = other(perm[0], perm[1]);
  std::array<bool, 3> flip{};
  for (int r = 0; r < 3; ++r) flip[std::size_t(perm[std::size_t(r)])] = m(r, perm[std::size_t(r)]) < 0.0;

  // The realigned transform (Header::realign_transform): flipped axes reversed, their origin moved to their
  // last voxel, then the axes permuted.
  for (int a = 0; a < 3; ++a)
    if (flip[std::size_t(a)]) {
      const double length = double(dims[std::size_t(a)] - 1) * g.spacing[std::size_t(a)];
      for (int n = 0; n < 3; ++n) {
        m.matrix()(n, a) = -m.matrix()(n, a);
        m.translation()[n] -= length * m.matrix()(n, a);
      }
    }
  for (int r = 0; r < 3; ++r) {
    const Eigen::RowVector3d row = m.matrix().row(r).head<3>();
    m.matrix().row(r).head<3>() = Eigen::RowVector3d(row[perm[0]], row[perm[1]], row[perm[2]]);
  }
  // tckedit's mask is the realigned image cropped to its set voxels and one more on each side where there is one
  // (roi.cpp, Adapter::Subset): the crop's first voxel moves the origin, axis after axis.
  Eigen::Vector3d spacing;
  MaskLookup lookup;
  const std::array<std::int64_t, 3> stride{1, dims[0], dims[0] * dims[1]};
  std::array<std::int64_t, 3> bottom{};
  for (int j = 0; j < 3; ++j) {
    const std::size_t a = std::size_t(perm[std::size_t(j)]);
    spacing[j] = g.spacing[a];
    const std::int64_t lo = flip[a] ? dims[a] - 1 - last[a] : first[a];
    const std::int64_t hi = flip[a] ? dims[a] - 1 - first[a] : last[a];
    bottom[std::size_t(j)] = lo > 0 ? lo - 1 : 0;
    lookup.dims[std::size_t(j)] = std::min(dims[a] - bottom[std::size_t(j)], hi + 2 - bottom[std::size_t(j)]);
    lookup.step[std::size_t(j)] = flip[a] ? -stride[a] : stride[a];
    if (flip[a]) lookup.offset += (dims[a] - 1) * stride[a];
    lookup.offset += bottom[std::size_t(j)] * lookup.step[std::size_t(j)];
  }
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) m.matrix()(i, 3) += double(bottom[std::size_t(j)]) * spacing[j] * m.matrix()(i, j);
  // tckedit's Mask: Transform(image).scanner2voxel, the inverse of voxel2scanner, in double; kept in float32.
  const Affine voxel_to_scanner = m * Eigen::DiagonalMatrix<double, 3>(spacing);
  const Eigen::Transform<float, 3, Eigen::AffineCompact> s = voxel_to_scanner.inverse().cast<float>();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) lookup.scanner_to_voxel[std::size_t(4 * r + c)] = s.matrix()(r, c);
  return lookup;
}

}  // namespace vxl
