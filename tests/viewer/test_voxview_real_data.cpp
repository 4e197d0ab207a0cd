// `voxview --render` opens every readable real fixture headless, as a converted .vxl and directly from
// the source file (converted first).
#include <filesystem>

#include "tests/real_fixture_outcomes.h"
#include "tests/test_support.h"
#include "viewer/platform/image_io.h"

namespace vxl {
namespace {

using test::Outcome;
using test::real;
using test::ScratchDir;

class VoxviewRealFixture : public ::testing::TestWithParam<std::string> {};

TEST_P(VoxviewRealFixture, RendersAsVxlAndDirectly) {
  VXL_REQUIRE_REAL_DATA();
  const std::string name = GetParam();
  if (!std::filesystem::exists(real(name))) GTEST_SKIP() << name << " is not in this copy of the fixtures";
  ScratchDir dir;
  const std::string vxl = dir.file("scene.vxl");
  auto convert = test::run_cli("convert '" + real(name) + "' '" + vxl + "'");
  ASSERT_EQ(convert.exit_code, 0) << convert.output;
  for (const std::string& input : {vxl, real(name)}) {
    const std::string png = dir.file("out.png");
    std::filesystem::remove(png);
    auto r = test::run_program(VOXVIEW_CLI, "'" + input + "' --render '" + png + "' --size 96x64 --mode axis");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    Image img = read_image(png);
    EXPECT_EQ(img.width, 96);
    EXPECT_EQ(img.height, 64);
  }
}

std::vector<std::string> readable_fixtures() {
  std::vector<std::string> names;
  for (const auto& [name, outcome] : test::expected_outcomes())
    if (outcome == Outcome::RoundTrip) names.push_back(name);
  return names;
}

std::string test_name(const ::testing::TestParamInfo<std::string>& info) { return test::fixture_test_name(info.param); }

INSTANTIATE_TEST_SUITE_P(Readable, VoxviewRealFixture, ::testing::ValuesIn(readable_fixtures()), test_name);

}  // namespace
}  // namespace vxl
