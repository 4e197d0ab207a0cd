#include "converter/readers/volume_image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <new>
#include <stdexcept>

#include "converter/readers/mrtrix_image.h"
#include "converter/readers/nifti_image.h"
#include "format/base/error.h"
#include "format/base/memory_available.h"

namespace vxl {
namespace {

// Bounds of a sane voxel-to-RAS mapping (mm): anything outside is a damaged header, and would draw or
// select nothing.
constexpr double kMinVoxelMm = 1e-6, kMaxVoxelMm = 1e4, kMaxOriginMm = 1e6;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

struct ImageFormat {
  const char* extension;
  const char* name;  // nullptr: read; otherwise the format refused
};
constexpr ImageFormat kImageFormats[] = {
    {".nii", nullptr},
    {".nii.gz", nullptr},
    {".mif", nullptr},
    {".mif.gz", nullptr},
    {".mih", nullptr},
    {".mgz", "FreeSurfer MGZ"},
    {".mgh", "FreeSurfer MGH"},
    {".hdr", "ANALYZE / two-file NIfTI (.hdr/.img)"},
    {".img", "ANALYZE / two-file NIfTI (.hdr/.img)"},
    {".nrrd", "NRRD"},
    {".nhdr", "NRRD"},
    {".mnc", "MINC"},
    {".dcm", "DICOM"},
    {".ima", "DICOM"},
    {".v", "ECAT"},
    {".img.gz", "ANALYZE / two-file NIfTI (.hdr/.img)"},
    {".hdr.gz", "ANALYZE / two-file NIfTI (.hdr/.img)"},
    {".nii.bz2", "bzip2-compressed NIfTI"},
    {".nii.zst", "zstd-compressed NIfTI"},
};

const ImageFormat* format_of(const std::string& path) {
  const std::string name = lower(path);
  const ImageFormat* best = nullptr;
  for (const ImageFormat& f : kImageFormats) {
    const std::string ext = f.extension;
    if (name.size() > ext.size() && name.ends_with(ext) && (!best || ext.size() > std::string(best->extension).size()))
      best = &f;
  }
  return best;
}

std::string mm(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

}  // namespace

bool is_image_name(const std::string& path) { return format_of(path) != nullptr; }

VolumeImage read_volume_image(const std::string& path, const ImageLimits& limits) {
  const ImageFormat* f = format_of(path);
  if (f && f->name)
    fail_unsupported(path, std::string(f->extension) + " (" + f->name +
                               ") is not supported; convert it to NIfTI (.nii/.nii.gz) or MRtrix (.mif) first, "
                               "e.g. with mrconvert");
  const std::string name = lower(path);
  if (name.ends_with(".mif") || name.ends_with(".mif.gz") || name.ends_with(".mih"))
    return read_mrtrix_image(path, limits);
  if (f) return read_nifti_image(path, limits);
  fail_unsupported(path, "not a known image file name: expected .nii, .nii.gz, .mif, .mif.gz or .mih");
}

void check_image_size(const std::string& path, const std::array<std::int64_t, 3>& dims, const ImageLimits& limits) {
  for (int a = 0; a < 3; ++a)
    if (dims[a] > limits.max_axis)
      fail_unsupported(path, "the image is " + std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" +
                                 std::to_string(dims[2]) + " voxels; at most " + std::to_string(limits.max_axis) +
                                 " along each axis are read (" + limits.reason + ")");
  const double voxels = double(dims[0]) * double(dims[1]) * double(dims[2]);
  if (voxels > double(limits.max_voxels))
    fail_unsupported(path, "the image has " + std::to_string(static_cast<std::uint64_t>(voxels)) +
                               " voxels per volume; at most " + std::to_string(limits.max_voxels) + " are read (" +
                               limits.reason + ")");
}

void reserve_values(VolumeImage& image, const std::string& path, std::uint64_t voxels) {
  try {
    image.values.reserve(static_cast<std::size_t>(voxels));
  } catch (const std::bad_alloc&) {
    fail_unsupported(path, "its " + std::to_string(voxels) + " voxels take " + std::to_string(4 * voxels) +
                               " bytes as float32 samples, more than can be allocated within " + memory_limit_text());
  } catch (const std::length_error&) {
    fail_unsupported(path, "its " + std::to_string(voxels) + " voxels cannot be held in memory");
  }
}

void check_voxel_to_ras(const std::string& path, const std::array<double, 16>& a, const std::string& source) {
  const std::string bounds = " (expected finite, each voxel axis " + mm(kMinVoxelMm) + " to " + mm(kMaxVoxelMm) +
                             " mm long, the origin within " + mm(kMaxOriginMm) + " mm of 0,0,0)";
  for (int i = 0; i < 12; ++i)
    if (!std::isfinite(a[i]))
      fail_input(path, std::nullopt, source + " is not finite: no voxel-to-RAS mapping" + bounds);
  double lengths[3];
  for (int col = 0; col < 3; ++col) {
    lengths[col] = std::hypot(a[col], a[4 + col], a[8 + col]);
    if (!(lengths[col] >= kMinVoxelMm && lengths[col] <= kMaxVoxelMm))
      fail_input(path, std::nullopt,
                 source + " makes voxel axis " + std::to_string(col) + " " + mm(lengths[col]) + " mm long" + bounds);
  }
  for (int row = 0; row < 3; ++row)
    if (std::abs(a[4 * row + 3]) > kMaxOriginMm)
      fail_input(path, std::nullopt,
                 source + " puts voxel 0,0,0 at " + mm(a[3]) + "," + mm(a[7]) + "," + mm(a[11]) + " mm" + bounds);
  // The determinant relative to the axes' lengths: the volume of the voxel against that of a cube.
  const double det =
      a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) + a[2] * (a[4] * a[9] - a[5] * a[8]);
  if (!(std::abs(det) > 1e-6 * lengths[0] * lengths[1] * lengths[2]))
    fail_input(path, std::nullopt, source + " is singular: its voxel axes are (nearly) coplanar" + bounds);
}

}  // namespace vxl
