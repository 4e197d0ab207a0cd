// A region of space that selects streamlines, with MRtrix tckedit's containment rules so that a selection
// can be compared with tckedit's one to one:
//
//   sphere  a point p is inside when |centre - p|^2 <= radius^2, computed in float32 as tckedit does
//           (so a point exactly on the surface is inside);
//   box     lo <= p <= hi on every axis (both faces inside);
//   mask    the image voxel nearest to p (p through the inverse of the image's voxel-to-RAS transform,
//           in float32, each index rounded half away from zero) exists and is non-zero, or holds the
//           chosen label.
//
// Each region also says which axis-aligned boxes it may touch (conservatively), so that a selection
// looks only at the voxels of a .vxl whose bounds it meets.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "converter/readers/volume_image.h"

namespace vxl {

using Point3f = std::array<float, 3>;

class Region {
 public:
  enum class Shape { Sphere, Box, Mask };

  static Region sphere(Point3f centre, float radius, std::string text);
  static Region box(Point3f lo, Point3f hi, std::string text);
  // `label`: the voxels holding exactly this value; none: every non-zero voxel. Throws vxl::Error (Usage)
  // naming `text` when no voxel is selected (an empty mask, or a label the image does not hold).
  static Region mask(const VolumeImage& image, std::optional<float> label, std::string text);

  Shape shape() const { return shape_; }
  // The argument it was made from, for messages and provenance.
  const std::string& text() const { return text_; }
  bool contains(const float* p) const;
  // A sphere's: its centre and radius, and the float32 squared distance contains() compares with radius_squared()
  // (tckedit's arithmetic), so that a caller keeping distances decides as contains() does.
  const Point3f& centre() const { return centre_; }
  float radius() const { return radius_; }
  float radius_squared() const { return radius2_; }
  float squared_distance(const float* p) const {
    const float dx = centre_[0] - p[0], dy = centre_[1] - p[1], dz = centre_[2] - p[2];
    return dx * dx + (dy * dy + dz * dz);  // summed as Eigen unrolls a sum of three (halves: x, then y + z)
  }
  // False only when no point of the box [lo, hi] can be inside (up to float rounding).
  bool may_touch(const float* lo, const float* hi) const;
  // A box [lo, hi] holding every point that can be inside (up to float rounding, widened by the same slack as
  // may_touch): a query can skip a point outside it without the exact test.
  void reach(float* lo, float* hi) const;
  // True only when every point of the box [lo, hi] is inside (up to float rounding, with the same slack
  // inwards); always false for a mask. A query need not test the points of a voxel such a region holds.
  bool holds_box(const float* lo, const float* hi) const;

 private:
  Region() = default;

  Shape shape_ = Shape::Sphere;
  std::string text_;
  Point3f centre_{}, lo_{}, hi_{};  // sphere centre; box corners (a mask's: the RAS box of its set voxels)
  float radius_ = 0, radius2_ = 0;
  // Mask: how a point finds its voxel (converter/readers/image_geometry.h, MaskLookup: RAS -> the cropped
  // realigned image's voxel, row-major 3 x 4, in float32), that image's sizes, and which of its voxels are selected
  // (1 byte each, n0 fastest; shared by the copies of a region).
  std::array<std::int64_t, 3> dims_{};
  std::shared_ptr<const std::vector<std::uint8_t>> set_;
  std::array<float, 12> ras_to_voxel_{};
};

// One row of a mask's RAS -> voxel affine (4 floats) applied to `p` in float32, in the order Eigen sums tckedit's
// affine product: (m0 p0 + m1 p1) + (m2 p2 + m3).
inline float mask_row(const float* m, const float* p) { return (m[0] * p[0] + m[1] * p[1]) + (m[2] * p[2] + m[3]); }

// Parses one region argument:
//   X,Y,Z,R                  a sphere (RAS mm), as tckedit writes it
//   box:X0,Y0,Z0,X1,Y1,Z1    a box between two corners (RAS mm)
//   FILE.nii[.gz]            a mask: its non-zero voxels
//   FILE.nii[.gz]:LABEL      one label of a parcellation
// Throws vxl::Error naming the argument: Usage (2) for a malformed or impossible region (a negative or
// non-finite radius, a box with a lower corner above the upper one, an empty mask, an absent label), and
// the image reader's errors (3, 4) for a file that cannot be read as an image.
Region parse_region(const std::string& text);

// Parses several region arguments, as parse_region does each: the spheres and boxes first, in order (so that a
// malformed one is reported before any file is read), then each image file once, however many arguments name
// it (with or without labels), one image held at a time; an argument given twice shares its voxels.
std::vector<Region> parse_regions(const std::vector<std::string>& texts);

}  // namespace vxl
