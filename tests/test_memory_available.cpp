// Converting without --memory-limit: the limit chosen from the source's size and the memory available, the CLI
// saying when the memory available limits it (and the output the same).
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

TEST(MemoryAvailable, TheDefaultLimitFollowsTheSourceWithinHalfOfWhatIsAvailable) {
  EXPECT_EQ(default_memory_limit(100 * MiB, 24 * GiB), 256 * MiB);      // at least 256 MiB
  EXPECT_EQ(default_memory_limit(640 * MiB, 24 * GiB), 720 * MiB);      // 9/8 of the source
  EXPECT_EQ(default_memory_limit(7 * GiB, 24 * GiB), 6 * GiB);          // the 10M set: at most 6 GiB
  EXPECT_EQ(default_memory_limit(7 * GiB, 4 * GiB), 2 * GiB);           // half of what is available
  EXPECT_EQ(default_memory_limit(1 * GiB, 10 * MiB), 64 * MiB);         // never under 64 MiB
  EXPECT_EQ(default_memory_limit(640 * MiB, std::nullopt), 512 * MiB);  // unknown: 1 GiB assumed available
  EXPECT_FALSE(limited_by_available_memory(640 * MiB, 24 * GiB));
  EXPECT_TRUE(limited_by_available_memory(640 * MiB, 1 * GiB));  // wants 720 MiB, has 512 MiB
  EXPECT_FALSE(limited_by_available_memory(100 * MiB, 512 * MiB));
}

TEST(MemoryAvailable, EnvironmentOverrides) {
  ::setenv("VOXLINES_MEMORY_AVAILABLE", "123M", 1);
  EXPECT_EQ(available_memory(), 123 * MiB);
  // Set but not a size: a usage error naming the variable, not a silent guess.
  ::setenv("VOXLINES_MEMORY_AVAILABLE", "abc", 1);
  try {
    (void)available_memory();
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("VOXLINES_MEMORY_AVAILABLE=abc: is not a memory size"), std::string::npos)
        << e.what();
  }
  ::unsetenv("VOXLINES_MEMORY_AVAILABLE");
  // Without it, /proc/meminfo (Linux) gives a figure.
  const auto real = available_memory();
  ASSERT_TRUE(real.has_value());
  EXPECT_GT(*real, 0u);
}

TEST(MemoryAvailable, ConvertSaysWhenTheMemoryAvailableLimitsIt) {
  ScratchDir dir;
  const std::string tck = dir.file("s.tck");
  ASSERT_EQ(run_cli("synth " + q(tck) + " --streamlines 4000").exit_code, 0);
  auto whole = run_cli("convert " + q(tck) + " " + q(dir.file("whole.vxl")) + " --threads 2");
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_EQ(whole.output.find("available"), std::string::npos) << whole.output;
  EXPECT_NE(whole.output.find("memory limit 256.0 MiB: 3 passes over the source"), std::string::npos) << whole.output;

  // Wants 256 MiB; 4 MiB are said to be available: the least limit, 64 MiB.
  auto streamed = test::run_program("VOXLINES_MEMORY_AVAILABLE=4M " VOXLINES_CLI,
                                    "convert " + q(tck) + " " + q(dir.file("streamed.vxl")) + " --threads 2");
  ASSERT_EQ(streamed.exit_code, 0) << streamed.output;
  EXPECT_NE(streamed.output.find("4.0 MiB of memory available: converting within --memory-limit 64M"),
            std::string::npos)
      << streamed.output;
  EXPECT_NE(streamed.output.find("passes over the source"), std::string::npos) << streamed.output;
  EXPECT_EQ(test::slurp(dir.file("whole.vxl")), test::slurp(dir.file("streamed.vxl")));
}

}  // namespace
}  // namespace vxl
