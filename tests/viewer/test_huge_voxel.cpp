// A voxel far larger than the scene (convert --voxel-size 1e8 ... 1e300) is drawn, not
// culled away by the near plane.
#include <filesystem>
#include <string>

#include "format/vxl_file.h"
#include "tests/test_support.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_io.h"

namespace vxl {
namespace {

using test::ScratchDir;

using test::lit_pixels;
using test::q;

test::CommandResult voxview(const std::string& args) { return test::run_program(VOXVIEW_CLI, args); }

// `convert --voxel-size 1e8` (up to 1e300) gives one voxel holding the whole tractogram, valid; the viewer
// draws that voxel, as at 1e6, rather than nothing ("0 voxels drawn"), which a near plane at 10^-4 of a far
// plane one voxel beyond the scene (i.e. 10 m away) would give.
TEST(VoxviewHugeVoxel, OneVoxelLargerThanTheSceneIsDrawn) {
  ScratchDir dir;
  auto r = test::run_cli("synth " + q(dir.file("in.tck")) + " --streamlines 30 --seed 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* size : {"1e6", "1e8", "1e12", "1e300"}) {
    SCOPED_TRACE(size);
    r = test::run_cli("convert " + q(dir.file("in.tck")) + " " + q(dir.file("big.vxl")) + " --voxel-size " + size);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const VxlFile f = VxlFile::open(dir.file("big.vxl"));
    ASSERT_EQ(f.meta().voxel_count, 1u);
    r = test::run_cli("verify " + q(dir.file("big.vxl")));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    for (const char* mode : {"axis", "opaque"}) {
      r = voxview(q(dir.file("big.vxl")) + " --render " + q(dir.file("big.png")) + " --size 64x64 --mode " + mode);
      ASSERT_EQ(r.exit_code, 0) << r.output;
      EXPECT_NE(r.output.find(" 1 voxels and "), std::string::npos) << mode << ": " << r.output;
      EXPECT_GT(lit_pixels(read_image(dir.file("big.png"))), 50) << mode;
    }
  }
}

}  // namespace
}  // namespace vxl
