// libFuzzer target: the legacy VTK reader on arbitrary bytes, then conversion of whatever it accepted.
#include "converter/convert.h"
#include "converter/readers/read_tractogram.h"
#include "format/error.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = vxl::fuzz::write_input(data, size, ".vtk");
  vxl::ConvertSettings s;
  s.threads = 1;
  try {
    vxl::convert_tractogram(vxl::read_vtk(path), path + ".vxl", s);
  } catch (const vxl::Error&) {
  }
  return 0;
}
