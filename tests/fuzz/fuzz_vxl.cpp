// libFuzzer target: opening, walking, exporting and verifying arbitrary bytes as a .vxl. open() must
// never let a later read go out of bounds, whatever verify() would say. Each input is tried as it is and
// again with its checksums recomputed, so that verify's structure checks behind the checksums see the
// damage too.
#include <vector>

#include "converter/export/export_tck.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/fuzz/fuzz_input.h"
#include "tests/reseal_checksums.h"

namespace {

void open_walk_verify(const std::string& path) {
  try {
    vxl::VxlFile f = vxl::VxlFile::open(path);
    for (std::size_t i = 0; i < f.voxels().size(); ++i)
      for (std::uint32_t k = 0; k < f.meta().stored_order_count; ++k) {
        vxl::OrderView o = f.order(i, k);
        volatile std::uint32_t sink = 0;
        for (std::uint32_t n = 0; n < o.count; ++n) sink = sink + o[n];
      }
    vxl::export_tck(f, path + ".tck");
    f.groups();
  } catch (const vxl::Error&) {
  }
  vxl::verify_vxl(path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  open_walk_verify(vxl::fuzz::write_input(data, size, ".vxl"));
  std::vector<std::uint8_t> resealed(data, data + size);
  if (vxl::test::reseal_checksums(resealed.data(), resealed.size()))
    open_walk_verify(vxl::fuzz::write_input(resealed.data(), resealed.size(), ".vxl"));
  return 0;
}
