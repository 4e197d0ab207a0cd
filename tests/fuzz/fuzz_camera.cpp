// libFuzzer target: voxview's saved-view parser (--camera FILE.json) on arbitrary text. Whatever it
// accepts must write back to JSON that parses to the same view.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "format/base/error.h"
#include "viewer/app/camera_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const vxl::app::SavedView view = vxl::app::parse_view_json(text, "fuzz.json");
    const std::string again = vxl::app::view_json(view);
    if (vxl::app::view_json(vxl::app::parse_view_json(again, "again.json")) != again) {
      std::fprintf(stderr, "fuzz_camera: a view written back reads otherwise\n");
      std::abort();
    }
  } catch (const vxl::Error&) {
  }
  return 0;
}
