// libFuzzer target: the TRK reader on arbitrary bytes (a .trk, or a .trk.gz when they start with the gzip
// magic, as the seeds from real .trk.gz files do), then on the same bytes gzipped, which must read the
// same, so that the TRK parser is fuzzed through the gzip path too; then conversion of whatever it accepted.
// scripts/fuzz runs it under -rss_limit_mb: a bomb the reader does not refuse is a finding.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>

#include <zlib.h>

#include "converter/convert/convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/base/error.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "fuzz_trk: %s\n", what);
  std::abort();
}

std::string gzip(const std::uint8_t* data, std::size_t size) {
  z_stream z{};
  if (deflateInit2(&z, 1, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK) std::abort();
  std::string out(deflateBound(&z, size) + 64, '\0');
  z.next_in = const_cast<Bytef*>(data);
  z.avail_in = static_cast<uInt>(size);
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  if (deflate(&z, Z_FINISH) != Z_STREAM_END) std::abort();
  out.resize(out.size() - z.avail_out);
  deflateEnd(&z);
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".trk");
  std::optional<vxl::Tractogram> plain;
  try {
    plain = vxl::read_trk(path);
  } catch (const vxl::Error&) {
  }
  // The same bytes gzipped must read the same (not converted again: the conversion would be the same).
  if (size < 2 || data[0] != 0x1F || data[1] != 0x8B) {
    const std::string gz = gzip(data, size);
    try {
      const vxl::Tractogram t =
          vxl::read_trk(vxl::fuzz::write_input(reinterpret_cast<const std::uint8_t*>(gz.data()), gz.size(), ".trk.gz"));
      if (!plain || t.offsets != plain->offsets || t.positions.size() != plain->positions.size() ||
          (!t.positions.empty() &&
           std::memcmp(t.positions.data(), plain->positions.data(), t.positions.size() * sizeof(float)) != 0))
        finding("the gzipped bytes read otherwise than the plain ones");
    } catch (const vxl::Error&) {
      if (plain) finding("the gzipped bytes were refused, the plain ones not");
    }
  }
  if (plain) {
    try {
      vxl::ConvertSettings s;
      s.memory_limit = 64u << 20;  // small buffers for small inputs; a limit does not change the bytes
      s.threads = 1;
      vxl::convert_tractogram(std::move(*plain), path + ".vxl", s);
    } catch (const vxl::Error&) {
    }
  }
  return 0;
}
