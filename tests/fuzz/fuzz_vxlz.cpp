// libFuzzer target: unpacking arbitrary bytes as a .vxlz package. A damaged package must be refused with
// a vxl::Error and leave nothing at the output path; one that unpacks must give a file verify accepts.
// Each input is tried as it is and again with its checksums recomputed: otherwise nearly every mutation
// stops at a checksum and the zlib, Draco and structure decoders behind them are never reached.
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/vxl_verify.h"
#include "tests/fuzz/fuzz_input.h"
#include "tests/reseal_checksums.h"

namespace {

void unpack_or_refuse(const std::string& path) {
  const std::string out = path + ".vxl";
  std::filesystem::remove(out);
  vxl::UnpackSettings settings;
  settings.threads = 1;
  try {
    vxl::unpack_vxlz(path, out, settings);
  } catch (const vxl::Error&) {
    if (std::filesystem::exists(out)) std::abort();  // a refused package left an output behind
    return;
  }
  if (!vxl::verify_vxl(out).valid) std::abort();  // unpacked, but not into a valid .vxl
  std::filesystem::remove(out);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  unpack_or_refuse(vxl::fuzz::write_input(data, size, ".vxlz"));
  std::vector<std::uint8_t> resealed(data, data + size);
  if (vxl::test::reseal_checksums(resealed.data(), resealed.size()))
    unpack_or_refuse(vxl::fuzz::write_input(resealed.data(), resealed.size(), ".vxlz"));
  return 0;
}
