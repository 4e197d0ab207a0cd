// libFuzzer target: the legacy VTK reader on arbitrary bytes, then conversion of whatever it accepted.
#include "converter/readers/read_tractogram.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vxl::fuzz::read_and_convert(vxl::fuzz::write_input(data, size, ".vtk"),
                              [](const std::string& path) { return vxl::read_vtk(path); });
  return 0;
}
