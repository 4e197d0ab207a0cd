#include "viewer/anatomy/nifti_volume.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "converter/readers/volume_image.h"

namespace vxl {

std::array<float, 2> percentile_window(const std::vector<float>& values, double low, double high) {
  // At most ~4M samples, taken at a fixed stride: the window of a large image in a fraction of a second.
  const std::size_t stride = std::max<std::size_t>(1, values.size() / (std::size_t(1) << 22));
  std::vector<float> picked;
  for (bool nonzero_only : {true, false}) {
    picked.clear();
    for (std::size_t i = 0; i < values.size(); i += stride)
      if (std::isfinite(values[i]) && (!nonzero_only || values[i] != 0.0f)) picked.push_back(values[i]);
    if (!picked.empty()) break;
  }
  if (picked.empty()) return {0, 1};
  auto at = [&](double percent) {
    const std::size_t k = static_cast<std::size_t>(std::llround(percent / 100.0 * double(picked.size() - 1)));
    std::nth_element(picked.begin(), picked.begin() + std::ptrdiff_t(k), picked.end());
    return picked[k];
  };
  return {at(low), at(high)};
}

Volume read_nifti_volume(const std::string& path) {
  // A 3-D texture: OpenGL promises 2048 texels along each axis, and the float copy must fit in memory
  // beside the lines.
  ImageLimits limits;
  limits.max_axis = 2048;
  limits.max_voxels = std::uint64_t(1) << 28;
  limits.reason = "voxview draws it as a 3-D texture of at most 2048 voxels along an axis and 2^28 voxels in all";
  VolumeImage image = read_volume_image(path, limits);
  Volume v;
  v.name = path;
  v.dims = image.dims;
  v.values = std::move(image.values);
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col)
      v.voxel_to_ras[col][row] = image.voxel_to_ras[4 * row + col];  // glm: [column][row]
  v.window = percentile_window(v.values, 2.0, 98.0);
  return v;
}

}  // namespace vxl
