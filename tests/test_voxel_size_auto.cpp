// `--voxel-size auto`: the rule (voxel_size_auto.h) on the figures of real sets and at its extremes, and
// the CLI: the same choice in memory and streamed, recorded in the file and shown by `info`.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "converter/voxel_size_auto.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::run_cli;
using test::ScratchDir;

// The synthetic sets' bounding box, mm.
const double kLo[3] = {-62, -89, -42}, kHi[3] = {62, 57, 63};

TEST(VoxelSizeAuto, FollowsThePointCount) {
  EXPECT_EQ(choose_voxel_size(8'123'048, kLo, kHi, 1.0).size, 10.0);  // 144k: the paper's 10 mm
  EXPECT_EQ(choose_voxel_size(56'531'616, kLo, kHi, 1.0).size, 8.0);  // 1M: cbrt(32768 V / N) = 8.2
  // 10M: 3.8, but at most 20 000 voxels of the half-filled box needs 3.62: rounded up to 4.
  EXPECT_EQ(choose_voxel_size(565'000'000, kLo, kHi, 1.0).size, 4.0);
  EXPECT_EQ(choose_voxel_size(5'650'000'000, kLo, kHi, 1.0).size, 4.0);  // 100M: 1.8, bounded likewise
}

TEST(VoxelSizeAuto, StepsAndVoxelCountBoundItFromBelow) {
  // 4 mm steps (a coarse tracking): at least 12 mm, although the count alone would give 3.8.
  EXPECT_EQ(choose_voxel_size(565'000'000, kLo, kHi, 4.0).size, 12.0);
  // A huge extent with few points: the 20 000-voxel bound, not the 10 mm cap.
  const double lo[3] = {0, 0, 0}, hi[3] = {1000, 1000, 1000};
  const double size = choose_voxel_size(1000, lo, hi, 1.0).size;
  EXPECT_GE(size, std::cbrt(0.5e9 / 20000) * (1 - 1e-12));
  EXPECT_LT(size, 40.0);
}

TEST(VoxelSizeAuto, DegenerateInputsGetAFiniteSize) {
  const double zero[3] = {0, 0, 0};
  const double inf = std::numeric_limits<double>::infinity();
  const double huge_lo[3] = {-inf, 0, 0}, huge_hi[3] = {inf, 1, 1};
  for (const VoxelSizeChoice& c : {choose_voxel_size(0, zero, zero, 0), choose_voxel_size(1, zero, zero, 0),
                                   choose_voxel_size(100, kLo, kHi, std::numeric_limits<double>::quiet_NaN()),
                                   choose_voxel_size(100, huge_lo, huge_hi, 1.0)}) {
    EXPECT_TRUE(std::isfinite(c.size) && c.size > 0) << c.reason;
    EXPECT_NE(c.reason.find("auto: "), std::string::npos);
  }
}

TEST(VoxelSizeAuto, CliChoosesTheSameInMemoryAndStreamedAndInfoShowsIt) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck");
  ASSERT_EQ(run_cli("synth " + q(tck) + " --streamlines 3000").exit_code, 0);
  auto a = run_cli("convert " + q(tck) + " " + q(dir.file("a.vxl")) + " --voxel-size auto --threads 2");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  auto b =
      run_cli("convert " + q(tck) + " " + q(dir.file("b.vxl")) + " --voxel-size auto --threads 2 --memory-limit 64M");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  EXPECT_EQ(test::slurp(dir.file("a.vxl")), test::slurp(dir.file("b.vxl")));  // PROV records the threads: same

  auto info = run_cli("info " + q(dir.file("a.vxl")) + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.output;
  const nlohmann::json j = nlohmann::json::parse(info.output);
  // 3000 streamlines (~170k points) in the synthetic box: far below 32k vertices per 10 mm voxel.
  EXPECT_EQ(j.at("voxel_size").get<double>(), 10.0);
  EXPECT_EQ(j.at("voxel_size_choice").get<std::string>().rfind("auto: 10 mm for ", 0), 0u);
  EXPECT_NE(run_cli("info " + q(dir.file("a.vxl"))).output.find("voxel size    10 mm (auto: 10 mm"), std::string::npos);

  // A given size records no choice.
  ASSERT_EQ(run_cli("convert " + q(tck) + " " + q(dir.file("c.vxl")) + " --voxel-size 10").exit_code, 0);
  EXPECT_FALSE(
      nlohmann::json::parse(run_cli("info " + q(dir.file("c.vxl")) + " --json").output).contains("voxel_size_choice"));
}

TEST(VoxelSizeAuto, CliRefusesOtherWords) {
  ScratchDir dir;
  auto r = run_cli("convert in.tck " + q(dir.file("x.vxl")) + " --voxel-size fast");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("expected a positive number of mm or auto, got 'fast'"), std::string::npos) << r.output;
  EXPECT_EQ(run_cli("convert in.tck " + q(dir.file("x.vxl")) + " --voxel-size -1").exit_code, 2);
}

}  // namespace
}  // namespace vxl
