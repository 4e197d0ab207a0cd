// libFuzzer target: TRX archives whose members come from the input and are stored deflated, so that the
// member checks (sizes against header.json, dtypes, offsets, groups, dpv/dps) and the deflated path are
// reached by every input; fuzz_trx mutates whole archives (their directories and compressed bytes).
// Input: records of [u8 name length][name][u32 LE data length][data], lengths cut to what is left.
// scripts/fuzz makes the seeds from the real .trx files.
#include <algorithm>
#include <cstring>
#include <string>

#include <zip.h>

#include "converter/convert/convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/base/error.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(nullptr, 0, ".trx");
  int error = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_TRUNCATE | ZIP_CREATE, &error);
  if (archive == nullptr) std::abort();
  std::size_t at = 0;
  while (at < size) {
    const std::size_t declared_name_len = data[at++];
    const std::size_t name_len = std::min<std::size_t>(declared_name_len, size - at);
    const std::string name(reinterpret_cast<const char*>(data + at), name_len);
    at += name_len;
    std::uint32_t len = 0;
    if (size - at >= 4) std::memcpy(&len, data + at, 4);
    at += std::min<std::size_t>(4, size - at);
    len = static_cast<std::uint32_t>(std::min<std::size_t>(len, size - at));
    zip_source_t* src = zip_source_buffer(archive, data + at, len, 0);
    at += len;
    if (src == nullptr) std::abort();
    const zip_int64_t index = zip_file_add(archive, name.c_str(), src, ZIP_FL_ENC_GUESS);
    if (index < 0) {  // e.g. a name given twice, or empty
      zip_source_free(src);
      continue;
    }
    zip_set_file_compression(archive, static_cast<zip_uint64_t>(index), ZIP_CM_DEFLATE, 1);
  }
  if (zip_close(archive) != 0) zip_discard(archive);
  vxl::fuzz::read_and_convert(path, [](const std::string& p) { return vxl::read_trx(p); });
  return 0;
}
