// libFuzzer target: the region parser (voxlines select --include ROI, voxview --include) on arbitrary text.
// A region it accepts must answer for any point without failing; a text that names an existing file is left
// out (an image read is fuzz_nifti's).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

#include "converter/selection/region.h"
#include "format/base/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::error_code ec;
  if (text.find('\0') != std::string::npos || std::filesystem::exists(text, ec)) return 0;
  try {
    const vxl::Region region = vxl::parse_region(text);
    const float points[][3] = {{0, 0, 0}, {1e30f, -1e30f, 0}, {NAN, 0, 0}, {-3.5f, 2.25f, 7}};
    for (const float* p : points) (void)region.contains(p);
    const float lo[3] = {-10, -10, -10}, hi[3] = {10, 10, 10};
    (void)region.may_touch(lo, hi);
    (void)region.holds_box(lo, hi);
  } catch (const vxl::Error&) {
  }
  return 0;
}
