// An anatomical image (NIfTI or MRtrix, read by converter/readers/volume_image.h) as the render-side Volume, with its
// default grey window: the 2nd and 98th percentiles of the image's non-zero voxels (the air around a head
// is 0 in most T1s and would otherwise pull the window down); of all voxels when every one is 0.
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
