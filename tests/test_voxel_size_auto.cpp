// `--voxel-size auto`: the rule (voxel_size_auto.h) on the figures of real sets and at its extremes, and
// the CLI: the same choice in memory and streamed, recorded in the file and shown by `info`.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "converter/convert/voxel_size_auto.h"
#include "format/base/error.h"
#include "tests/mrtrix_test_files.h"
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

// The lower bounds raise the size within the list, never beyond 10 mm: 4 mm steps (a coarse tracking)
// would ask for 12 mm and a huge extent with few points for 29 mm; both got those sizes, off the list.
TEST(VoxelSizeAuto, StepsAndVoxelCountBoundItFromBelowWithinTheList) {
  const VoxelSizeChoice coarse = choose_voxel_size(565'000'000, kLo, kHi, 4.0);
  EXPECT_EQ(coarse.size, 10.0);
  EXPECT_NE(coarse.reason.find("12 mm would meet the step and voxel-count bounds, 10 mm is the largest it chooses"),
            std::string::npos)
      << coarse.reason;
  const double lo[3] = {0, 0, 0}, hi[3] = {1000, 1000, 1000};
  EXPECT_EQ(choose_voxel_size(1000, lo, hi, 1.0).size, 10.0);
  EXPECT_EQ(choose_voxel_size(565'000'000, kLo, kHi, 2.0).size, 6.0);  // 3.8 from the count, at least 6 for the steps
}

// Whatever the counts, extents and steps, the size is one of the list, at most 10 mm: the README's promise.
TEST(VoxelSizeAuto, EveryChoiceIsAListedSizeOfAtMostTenMm) {
  const std::vector<double> listed = {1, 1.25, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7, 8, 10};
  for (const std::uint64_t points : {std::uint64_t{1}, std::uint64_t{1000}, std::uint64_t{1} << 40})
    for (const double extent : {0.0, 1e-3, 1.0, 124.0, 1e4, 1e7, 1e9})
      for (const double step : {0.0, 0.01, 1.0, 3.0, 6.0}) {
        const double lo[3] = {-extent / 2, 0, 0}, hi[3] = {extent / 2, extent, extent / 3};
        const VoxelSizeChoice c = choose_voxel_size(points, lo, hi, step);
        EXPECT_NE(std::find(listed.begin(), listed.end(), c.size), listed.end())
            << points << " " << extent << " " << step << ": " << c.reason;
      }
}

// What no listed size can convert is refused by auto itself, with the size to give, instead of a size
// the conversion then refused (1e30 mm extents: auto chose 3.07e3 mm, then exit 4).
TEST(VoxelSizeAuto, WhatNoListedSizeConvertsIsRefusedWithTheSizeToGive) {
  auto error_of = [](std::uint64_t points, const double lo[3], const double hi[3], double step) -> std::string {
    try {
      (void)choose_voxel_size(points, lo, hi, step, "in.tck");
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
      return e.what();
    }
    return "no error";
  };
  const double far_lo[3] = {-5e29, 0, 0}, far_hi[3] = {5e29, 1, 1};
  EXPECT_NE(error_of(100, far_lo, far_hi, 1.0).find("in.tck: --voxel-size auto: the points span 1e+30 mm"),
            std::string::npos)
      << error_of(100, far_lo, far_hi, 1.0);
  EXPECT_NE(error_of(100, far_lo, far_hi, 1.0).find("give --voxel-size 1e+21 or larger"), std::string::npos);
  const double inf = std::numeric_limits<double>::infinity();
  const double inf_lo[3] = {-inf, 0, 0}, inf_hi[3] = {inf, 1, 1};
  EXPECT_NE(error_of(100, inf_lo, inf_hi, 1.0), "no error");
  EXPECT_NE(error_of(100, kLo, kHi, 97.0).find("steps of 97 mm (RMS)"), std::string::npos)
      << error_of(100, kLo, kHi, 97.0);
  EXPECT_NE(error_of(100, kLo, kHi, 97.0).find("give --voxel-size 291 or larger"), std::string::npos);
}

TEST(VoxelSizeAuto, DegenerateInputsGetAListedSize) {
  const double zero[3] = {0, 0, 0};
  const double none_lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::infinity()};
  const double none_hi[3] = {-none_lo[0], -none_lo[1], -none_lo[2]};
  for (const VoxelSizeChoice& c : {choose_voxel_size(0, zero, zero, 0), choose_voxel_size(1, zero, zero, 0),
                                   choose_voxel_size(100, kLo, kHi, std::numeric_limits<double>::quiet_NaN()),
                                   choose_voxel_size(0, none_lo, none_hi, 0)}) {
    EXPECT_TRUE(c.size >= 1 && c.size <= 10) << c.reason;
    EXPECT_EQ(c.reason.find("inf"), std::string::npos) << c.reason;
    EXPECT_NE(c.reason.find("auto: "), std::string::npos);
  }
  // An empty input's reason says so (it read "-inf x -inf x -inf mm").
  EXPECT_EQ(choose_voxel_size(0, none_lo, none_hi, 0).reason, "auto: 10 mm (no points to choose from)");
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

// Through the CLI, in memory and streamed: 1e30 mm extents are refused by auto (exit 4) with the size to
// give, and nothing is written.
TEST(VoxelSizeAuto, CliRefusesWhatNoListedSizeConverts) {
  ScratchDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::string tck = dir.file("far.tck"), out = dir.file("far.vxl");
  test::write_mrtrix_file(tck, "mrtrix tracks", "Float32LE",
                          test::raw<float>({-5e29f, 0, 0, 5e29f, 0, 0, nan, nan, nan, inf, inf, inf}));
  for (const char* extra : {"", " --memory-limit 64M"}) {
    const auto r = run_cli("convert " + q(tck) + " " + q(out) + " --voxel-size auto" + extra);
    EXPECT_EQ(r.exit_code, 4) << r.output;
    EXPECT_NE(r.output.find("--voxel-size auto: the points span 1e+30 mm"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));
  }
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
