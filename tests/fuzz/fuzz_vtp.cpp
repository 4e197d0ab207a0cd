// libFuzzer target: the VTP (VTK XML) reader on arbitrary bytes, then conversion of whatever it accepted.
#include "converter/convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/error.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".vtp");
  vxl::ConvertSettings s;
  s.threads = 1;
  try {
    vxl::convert_tractogram(vxl::read_vtp(path), path + ".vxl", s);
  } catch (const vxl::Error&) {
  }
  return 0;
}
