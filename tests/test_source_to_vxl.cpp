// The one policy that turns a source into a .vxl for both programs (converter/convert/source_to_vxl.h): the limit a
// TCK streams within, that every limit writes the same bytes, and that open_as_vxl leaves no temporary file behind.
#include <cstdlib>
#include <filesystem>
#include <string>

#include "converter/convert/source_to_vxl.h"
#include "converter/export/tck_writer.h"
#include "converter/pipeline/memory_budget.h"
#include "format/base/error.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::ScratchDir;

std::string synth_tck(const ScratchDir& dir, int streamlines) {
  const std::string tck = dir.file("s.tck");
  const test::CommandResult r = test::run_cli("synth " + q(tck) + " --streamlines " + std::to_string(streamlines));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return tck;
}

std::vector<char> mapped_bytes(const VxlFile& f) {
  return {reinterpret_cast<const char*>(f.bytes().data()),
          reinterpret_cast<const char*>(f.bytes().data()) + f.bytes().size()};
}

TEST(SourceToVxl, ATckStreamsWithinALimitChosenFromItsSizeAndSaysWhenMemoryIsShort) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 4000);
  SourceConversion conversion;
  std::string notice;
  conversion.notice = [&](const std::string& line) { notice += line; };
  const SourceConversionReport whole = convert_source(tck, dir.file("whole.vxl"), conversion);
  EXPECT_TRUE(whole.streamed);
  EXPECT_EQ(whole.memory_limit, 256ull << 20);  // the least default, for a small source
  EXPECT_TRUE(notice.empty()) << notice;

  ::setenv("VOXLINES_MEMORY_AVAILABLE", "4M", 1);
  const SourceConversionReport chosen = convert_source(tck, dir.file("chosen.vxl"), conversion);
  ::unsetenv("VOXLINES_MEMORY_AVAILABLE");
  EXPECT_TRUE(chosen.streamed);
  EXPECT_EQ(chosen.memory_limit, 64ull << 20);
  EXPECT_NE(notice.find(tck + ": 4.0 MiB of memory available: converting within --memory-limit 64M"), std::string::npos)
      << notice;
  EXPECT_EQ(test::slurp(dir.file("whole.vxl")), test::slurp(dir.file("chosen.vxl")));
}

// A chosen limit is raised where the source needs more (here: two batches each holding one streamline of 6M
// points whole, 288 MB, over the least default of 256 MiB); a limit given is not.
TEST(SourceToVxl, AChosenLimitIsRaisedWhereTheSourceNeedsMore) {
  ScratchDir dir;
  const std::string tck = dir.file("long.tck");
  {
    std::vector<float> xyz(3 * 6'000'000);
    for (std::size_t i = 0; i < xyz.size() / 3; ++i) xyz[3 * i + 2] = static_cast<float>(i) * 1e-5f;
    TckWriter w(tck, 1);
    w.add(xyz);
    w.finish();
  }
  SourceConversion conversion;
  conversion.settings.threads = 2;
  const SourceConversionReport raised = convert_source(tck, dir.file("raised.vxl"), conversion);
  EXPECT_GT(raised.memory_limit, 288'000'000u);
  EXPECT_EQ(raised.summary.points, 6'000'000u);
  conversion.settings.memory_limit = 256ull << 20;
  EXPECT_THROW(convert_source(tck, dir.file("given.vxl"), conversion), MemoryLimitTooSmall);
  EXPECT_FALSE(std::filesystem::exists(dir.file("given.vxl")));
}

TEST(SourceToVxl, OpenAsVxlStreamsThroughATemporaryFileItRemoves) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 4000);
  const std::string temporary = dir.file("tmp");
  std::filesystem::create_directories(temporary);
  SourceConversion conversion;
  ASSERT_EQ(convert_source(tck, dir.file("whole.vxl"), conversion).memory_limit, 256ull << 20);
  conversion.settings.memory_limit = 20ull << 20;
  const OpenedSource opened = open_as_vxl(tck, conversion, temporary);
  EXPECT_TRUE(opened.report.streamed);
  EXPECT_GE(opened.report.summary.passes, 3u);
  EXPECT_EQ(std::filesystem::path(opened.temporary_path).parent_path(), std::filesystem::path(temporary));
  EXPECT_TRUE(opened.temporary_path.ends_with("-s.tck.vxl")) << opened.temporary_path;
  EXPECT_EQ(opened.file.path(), tck) << "named by its source in errors and group names, not by the removed file";
  EXPECT_FALSE(std::filesystem::exists(opened.temporary_path));
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
  EXPECT_EQ(mapped_bytes(opened.file), test::slurp(dir.file("whole.vxl")));
}

TEST(SourceToVxl, OpenAsVxlLeavesNothingWhenItFails) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 2000);
  const std::string temporary = dir.file("tmp");
  std::filesystem::create_directories(temporary);
  // A limit too small for the work: refused by the streamed conversion before it writes.
  SourceConversion too_small;
  too_small.settings.memory_limit = 4ull << 20;
  try {
    (void)open_as_vxl(tck, too_small, temporary);
    ADD_FAILURE() << "a 4 MiB limit was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
  // A TCK cut inside its header (a truncated download), streamed and in memory. (A TCK cut inside its data is
  // read up to its last whole streamline, as MRtrix does.)
  std::filesystem::resize_file(tck, 20);
  for (const std::uint64_t limit : {std::uint64_t(20) << 20, std::uint64_t(0)}) {
    SCOPED_TRACE(limit ? "streamed" : "in memory");
    SourceConversion conversion;
    conversion.settings.memory_limit = limit;
    try {
      (void)open_as_vxl(tck, conversion, temporary);
      ADD_FAILURE() << "a truncated TCK was opened";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_EQ(e.file(), tck) << e.what();
    }
    EXPECT_TRUE(std::filesystem::is_empty(temporary));
  }
  // TSF values are attached in memory only: a limit with them is refused before anything is written.
  SourceConversion with_tsf;
  with_tsf.settings.memory_limit = 20ull << 20;
  with_tsf.tsf = {dir.file("values.tsf")};
  try {
    (void)open_as_vxl(dir.file("whole.tck"), with_tsf, temporary);
    ADD_FAILURE() << "--memory-limit with --tsf was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(temporary));
}

}  // namespace
}  // namespace vxl
