// libFuzzer target: unpacking arbitrary bytes as a .vxlz package. A damaged package must be refused with
// a vxl::Error and leave nothing at the output path; one that unpacks must give a file verify accepts.
// Each input is tried as it is and again with its checksums recomputed: otherwise nearly every mutation
// stops at a checksum and the zlib, Draco and structure decoders behind them are never reached.
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include "converter/package/unpack.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"
#include "format/vxl_verify.h"
#include "format/vxlz_package.h"
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

// The first look a viewer unpacks while a package arrives: its coarsest level alone, from the first bytes that hold
// it (a prefix: the positions' checksum cannot be checked, so damaged positions reach the decoders).
void unpack_first_level_or_refuse(const std::uint8_t* data, std::size_t size, const std::string& path) {
  const std::string out = path + ".level.vxl";
  std::filesystem::remove(out);
  auto prefix = [&](std::size_t n) {
    auto* copy = static_cast<std::uint8_t*>(std::malloc(n > 0 ? n : 1));
    std::memcpy(copy, data, n);
    return vxl::VxlzFile::open_prefix(vxl::MappedFile::adopt(path, copy, n));
  };
  try {
    const std::vector<vxl::ShippedLevel> levels = vxl::shipped_levels(prefix(size));
    if (levels.empty() || levels[0].level == 0 || levels[0].bytes > size) return;
    vxl::UnpackSettings settings;
    settings.threads = 1;
    settings.level = levels[0].level;
    vxl::unpack_vxlz(prefix(static_cast<std::size_t>(levels[0].bytes)), out, settings);
  } catch (const vxl::Error&) {
    if (std::filesystem::exists(out)) std::abort();
    return;
  }
  if (!vxl::verify_vxl(out).valid) std::abort();
  std::filesystem::remove(out);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".vxlz");
  unpack_or_refuse(path);
  unpack_first_level_or_refuse(data, size, path);
  std::vector<std::uint8_t> resealed(data, data + size);
  if (vxl::test::reseal_checksums(resealed.data(), resealed.size())) {
    const std::string resealed_path = vxl::fuzz::write_input(resealed.data(), resealed.size(), ".vxlz");
    unpack_or_refuse(resealed_path);
    unpack_first_level_or_refuse(resealed.data(), resealed.size(), resealed_path);
  }
  return 0;
}
