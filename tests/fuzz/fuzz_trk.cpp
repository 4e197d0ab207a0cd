// libFuzzer target: the TRK reader on arbitrary bytes (a .trk, or a .trk.gz when they start with the gzip
// magic, as the seeds from real .trk.gz files do), then on the same bytes gzipped, so that the TRK parser
// is fuzzed through the gzip path too; then conversion of whatever it accepted. scripts/fuzz runs it under
// -rss_limit_mb: a bomb the reader does not refuse is a finding.
#include <string>

#include <zlib.h>

#include "convert.h"
#include "error.h"
#include "fuzz_input.h"
#include "read_tractogram.h"

namespace {

void read_and_convert(const std::string& path) {
  try {
    vxl::Tractogram t = vxl::read_trk(path);
    vxl::ConvertSettings s;
    s.threads = 1;
    vxl::convert_tractogram(std::move(t), path + ".vxl", s);
  } catch (const vxl::Error&) {
  }
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
  read_and_convert(vxl::fuzz::write_input(data, size, ".trk"));
  const std::string gz = gzip(data, size);
  read_and_convert(vxl::fuzz::write_input(reinterpret_cast<const std::uint8_t*>(gz.data()), gz.size(), ".trk.gz"));
  return 0;
}
