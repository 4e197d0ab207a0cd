// libFuzzer target: unpacking arbitrary bytes as a .vxlz package. A damaged package must be refused with
// a vxl::Error and leave nothing at the output path; one that unpacks must give a file verify accepts.
#include <cstdlib>
#include <filesystem>

#include "error.h"
#include "fuzz_input.h"
#include "unpack.h"
#include "vxl_verify.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".vxlz");
  const std::string out = path + ".vxl";
  std::filesystem::remove(out);
  vxl::UnpackSettings settings;
  settings.threads = 1;
  try {
    vxl::unpack_vxlz(path, out, settings);
  } catch (const vxl::Error&) {
    if (std::filesystem::exists(out)) std::abort();  // a refused package left an output behind
    return 0;
  }
  if (!vxl::verify_vxl(out).valid) std::abort();  // unpacked, but not into a valid .vxl
  std::filesystem::remove(out);
  return 0;
}
