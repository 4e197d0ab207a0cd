// voxview's command line: a mistyped option gets the nearest one, an unknown view the list of views, and
// messages about options carry no file name.
#include "tests/test_support.h"

namespace vxl {
namespace {

TEST(VoxviewCommandLine, TyposAndUnknownViewsSayWhatIsKnown) {
  const test::CommandResult typo = test::run_program(VOXVIEW_CLI, "x.vxl --render x.png --opacty 0.5");
  EXPECT_EQ(typo.exit_code, 2);
  EXPECT_NE(typo.output.find("unknown option --opacty; did you mean --opacity?"), std::string::npos) << typo.output;
  test::ScratchDir dir;
  ASSERT_EQ(test::run_cli("synth " + test::q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  const test::CommandResult view = test::run_program(
      VOXVIEW_CLI, test::q(dir.file("a.tck")) + " --render " + test::q(dir.file("a.png")) + " --view axil");
  EXPECT_EQ(view.exit_code, 2);
  EXPECT_NE(view.output.find("unknown view 'axil' (expected axial,"), std::string::npos) << view.output;
  EXPECT_EQ(view.output.find("<input>"), std::string::npos) << view.output;
}

}  // namespace
}  // namespace vxl
