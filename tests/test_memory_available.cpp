// Converting without --memory-limit: a TCK whose conversion in memory would not fit is streamed (and the
// output is the same); the decision, and the CLI saying so.
#include <cstdlib>

#include <gtest/gtest.h>

#include "converter/convert/memory_choice.h"
#include "format/base/memory_available.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::run_cli;
using test::ScratchDir;

constexpr std::uint64_t MiB = 1ull << 20, GiB = 1ull << 30;

TEST(MemoryAvailable, StreamsOnlyWhenTheEstimateDoesNotFit) {
  EXPECT_EQ(in_memory_estimate(100 * MiB), 300 * MiB);
  EXPECT_FALSE(automatic_memory_limit(100 * MiB, 1 * GiB));          // 300 MiB of 1 GiB
  EXPECT_FALSE(automatic_memory_limit(170 * MiB, 1 * GiB));          // 510 MiB: within half
  EXPECT_EQ(automatic_memory_limit(180 * MiB, 1 * GiB), 512 * MiB);  // 540 MiB: streamed within half
  EXPECT_EQ(automatic_memory_limit(7 * GiB, 24 * GiB), 6 * GiB);     // the 10M set on a quiet 24 GiB machine
  EXPECT_EQ(automatic_memory_limit(7 * GiB, 22 * GiB), 6 * GiB);     // the 10M set: at most 6 GiB
  EXPECT_EQ(automatic_memory_limit(1 * GiB, 10 * MiB), 64 * MiB);    // at least 64 MiB
}

TEST(MemoryAvailable, EnvironmentOverrides) {
  ::setenv("VOXLINES_MEMORY_AVAILABLE", "123M", 1);
  EXPECT_EQ(available_memory(), 123 * MiB);
  ::unsetenv("VOXLINES_MEMORY_AVAILABLE");
  // Without it, /proc/meminfo (Linux) gives a figure.
  const auto real = available_memory();
  ASSERT_TRUE(real.has_value());
  EXPECT_GT(*real, 0u);
}

TEST(MemoryAvailable, ConvertStreamsWhatDoesNotFitAndSaysSo) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck");
  ASSERT_EQ(run_cli("synth " + q(tck) + " --streamlines 4000").exit_code, 0);
  auto whole = run_cli("convert " + q(tck) + " " + q(dir.file("whole.vxl")) + " --threads 2");
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_EQ(whole.output.find("streaming it"), std::string::npos) << whole.output;

  // ~2.7 MB of TCK: about 8 MB in memory, more than the 4 MiB said to be available.
  auto streamed = test::run_program("VOXLINES_MEMORY_AVAILABLE=4M " VOXLINES_CLI,
                                    "convert " + q(tck) + " " + q(dir.file("streamed.vxl")) + " --threads 2");
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_NE(streamed.output.find("of the 4.0 MiB available: streaming it within --memory-limit 64M"), std::string::npos)
      << streamed.output;
  EXPECT_NE(streamed.output.find("passes over the source"), std::string::npos) << streamed.output;
  EXPECT_EQ(test::slurp(dir.file("whole.vxl")), test::slurp(dir.file("streamed.vxl")));
}

}  // namespace
}  // namespace vxl
