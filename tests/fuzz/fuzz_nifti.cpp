// libFuzzer target: the image reader of voxview --image and select's masks (read_volume_image) on
// arbitrary bytes, as a .nii and as a .mif (named .gz when they start with the gzip magic, as the reader
// refuses gzip data under another name). Whatever
// it accepts must be whole: as many values as voxels, all finite, and a sane voxel-to-RAS mapping.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "converter/readers/volume_image.h"
#include "format/base/error.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "fuzz_nifti: %s\n", what);
  std::abort();
}

void read(const std::string& path) {
  try {
    const vxl::VolumeImage v = vxl::read_volume_image(path);
    if (v.values.size() != static_cast<std::size_t>(v.dims[0] * v.dims[1] * v.dims[2]))
      finding("values and dims disagree");
    for (float x : v.values)
      if (!std::isfinite(x)) finding("a value is not finite");
    for (double m : v.voxel_to_ras)
      if (!std::isfinite(m)) finding("the voxel-to-RAS mapping is not finite");
  } catch (const vxl::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const bool gzipped = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
  read(vxl::fuzz::write_input(data, size, gzipped ? ".nii.gz" : ".nii"));
  read(vxl::fuzz::write_input(data, size, gzipped ? ".mif.gz" : ".mif"));
  return 0;
}
