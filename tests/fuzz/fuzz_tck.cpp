// libFuzzer target: the TCK reader on arbitrary bytes, then conversion of whatever it accepted. The
// streaming reader must read the same (or fail with the same error), and the memory-limited conversion
// must write the same bytes (or refuse the limit).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>

#include "converter/convert/convert.h"
#include "converter/convert/streaming_convert.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/tck_stream.h"
#include "format/base/error.h"
#include "tests/fuzz/fuzz_input.h"

namespace {

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "fuzz_tck: %s\n", what);
  std::abort();
}

std::string read_all(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// TckStream with a tiny buffer and batches, so that triplets and streamlines straddle every boundary.
void check_stream(const std::string& path, const vxl::Tractogram* whole, const std::string& error) {
  try {
    vxl::TckStream stream(path, 1 << 20, 36);
    vxl::Tractogram all, batch;
    while (stream.next(batch, 3))
      for (std::uint64_t k = 0; k < batch.streamline_count(); ++k)
        all.add_streamline(batch.positions.data() + 3 * batch.offsets[k], batch.offsets[k + 1] - batch.offsets[k]);
    if (!whole) finding("TckStream accepted what read_tck refused");
    if (all.offsets != whole->offsets || all.positions.size() != whole->positions.size() ||
        (!all.positions.empty() &&
         std::memcmp(all.positions.data(), whole->positions.data(), all.positions.size() * sizeof(float)) != 0))
      finding("TckStream read other streamlines than read_tck");
    if (stream.source().warnings != whole->source.warnings || stream.source().xxh3_128 != whole->source.xxh3_128)
      finding("TckStream gave other provenance than read_tck");
  } catch (const vxl::Error& e) {
    if (whole || error != e.what()) finding("TckStream failed otherwise than read_tck");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".tck");
  vxl::ConvertSettings s;
  s.threads = 1;
  s.memory_limit = 64u << 20;  // small buffers for small inputs; a limit does not change the bytes
  std::optional<vxl::Tractogram> t;
  std::string read_error;
  try {
    t = vxl::read_tck(path);
  } catch (const vxl::Error& e) {
    read_error = e.what();
  }
  check_stream(path, t ? &*t : nullptr, read_error);
  bool converted = false;
  if (t) {
    try {
      vxl::convert_tractogram(std::move(*t), path + ".vxl", s);
      converted = true;
    } catch (const vxl::Error&) {
    }
  }
  if (converted) {
    try {
      vxl::convert_streaming(path, path + ".limited.vxl", s);
      if (read_all(path + ".vxl") != read_all(path + ".limited.vxl"))
        finding("the limited conversion wrote other bytes");
    } catch (const vxl::Error& e) {
      if (std::string(e.what()).find("--memory-limit") == std::string::npos) finding("the limited conversion failed");
    }
  }
  return 0;
}
