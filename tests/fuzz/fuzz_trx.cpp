// libFuzzer target: the TRX reader on arbitrary bytes, then conversion of whatever it accepted.
#include "converter/convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/error.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".trx");
  try {
    vxl::Tractogram t = vxl::read_trx(path);
    vxl::ConvertSettings s;
    s.threads = 1;
    vxl::convert_tractogram(std::move(t), path + ".vxl", s);
  } catch (const vxl::Error&) {
  }
  return 0;
}
