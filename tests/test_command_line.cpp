// The command line's rough edges: a convert output that is not .vxl, a source given where a .vxl is
// expected, and mistyped commands and options answered with the nearest known name.
#include <filesystem>

#include <gtest/gtest.h>

#include "converter/command_line_typos.h"
#include "converter/convert/convert.h"
#include "converter/readers/source_formats.h"
#include "converter/synth/synth.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::q;
using test::run_cli;
using test::ScratchDir;

TEST(CommandLine, ConvertRefusesAnOutputThatIsNotVxl) {
  ScratchDir dir;
  ASSERT_EQ(run_cli("synth " + q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  for (const char* name : {"out.tck", "out", "out.trx"}) {
    const test::CommandResult r = run_cli("convert " + q(dir.file("a.tck")) + " " + q(dir.file(name)));
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.output;
    EXPECT_NE(r.output.find("voxlines export"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file(name))) << name;
  }
  EXPECT_EQ(run_cli("convert " + q(dir.file("a.tck")) + " " + q(dir.file("OUT.VXL"))).exit_code, 0);
}

TEST(CommandLine, InfoAndVerifyNameTheFormatOfASourceGivenForAVxl) {
  ScratchDir dir;
  ASSERT_EQ(run_cli("synth " + q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  const test::CommandResult info = run_cli("info " + q(dir.file("a.tck")));
  EXPECT_EQ(info.exit_code, 3) << info.output;
  EXPECT_NE(info.output.find("this is an MRtrix TCK file, not a .vxl file"), std::string::npos) << info.output;
  const test::CommandResult verify = run_cli("verify " + q(dir.file("a.tck")));
  EXPECT_EQ(verify.exit_code, 1) << verify.output;
  EXPECT_NE(verify.output.find("MRtrix TCK"), std::string::npos) << verify.output;
  test::write_file(dir.file("t.trk"), {'T', 'R', 'A', 'C', 'K', 0, 0, 0, 0, 0});
  EXPECT_NE(run_cli("info " + q(dir.file("t.trk"))).output.find("TrackVis TRK"), std::string::npos);
}

// --positions names what it takes, in convert and unpack, instead of CLI11's transformer table.
TEST(CommandLine, APositionEncodingThatIsNotKnownSaysWhichAre) {
  ScratchDir dir;
  ASSERT_EQ(run_cli("synth " + q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  for (const std::string value : {"float64", "0"}) {
    const test::CommandResult r =
        run_cli("convert " + q(dir.file("a.tck")) + " " + q(dir.file("a.vxl")) + " --positions " + value);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("--positions: expected packed or float32, got '" + value + "'"), std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("a.vxl")));
  }
  EXPECT_EQ(run_cli("convert " + q(dir.file("a.tck")) + " " + q(dir.file("a.vxl")) + " --positions float32").exit_code,
            0);
}

// --threads takes a whole number (0: all cores), in every command that has it, and says so otherwise.
TEST(CommandLine, AThreadCountThatIsNotAWholeNumberSaysSo) {
  ScratchDir dir;
  ASSERT_EQ(run_cli("synth " + q(dir.file("a.tck")) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + q(dir.file("a.tck")) + " " + q(dir.file("a.vxl")) + " --threads 1").exit_code, 0);
  const std::string commands[] = {"convert " + q(dir.file("a.tck")) + " " + q(dir.file("b.vxl")),
                                  "pack " + q(dir.file("a.vxl")) + " " + q(dir.file("a.vxlz"))};
  for (const std::string& command : commands)
    for (const std::string value : {"-1", "x", "1.5"}) {
      const test::CommandResult r = run_cli(command + " --threads " + value);
      EXPECT_EQ(r.exit_code, 2) << command << ": " << r.output;
      EXPECT_NE(r.output.find("--threads: expected a whole number of threads (0: all cores), got '" + value + "'"),
                std::string::npos)
          << r.output;
    }
}

TEST(CommandLine, TyposGetTheNearestName) {
  EXPECT_EQ(nearest_name("convet", {"convert", "info", "verify"}), "convert");
  EXPECT_EQ(nearest_name("--voxelsize", {"--voxel-size", "--verbose"}), "--voxel-size");
  EXPECT_EQ(nearest_name("frobnicate", {"convert", "info"}), "");
  const test::CommandResult command = run_cli("convet a b");
  EXPECT_EQ(command.exit_code, 2);
  EXPECT_NE(command.output.find("unknown command 'convet'; did you mean 'convert'?"), std::string::npos)
      << command.output;
  const test::CommandResult option = run_cli("convert a.tck b.vxl --voxelsize 5");
  EXPECT_EQ(option.exit_code, 2);
  EXPECT_NE(option.output.find("unknown option --voxelsize; did you mean --voxel-size?"), std::string::npos)
      << option.output;
  EXPECT_NE(option.output.find("convert --help"), std::string::npos) << option.output;
  // A known option with a bad value keeps the parser's own message.
  const test::CommandResult value = run_cli("convert a.tck b.vxl --levels 99");
  EXPECT_EQ(value.exit_code, 2);
  EXPECT_EQ(value.output.find("unknown option"), std::string::npos) << value.output;
}

// The text of `help` from `from` up to `to` (the next option's name), empty when `from` is missing.
std::string help_part(const std::string& help, const std::string& from, const std::string& to) {
  const std::size_t start = help.find(from);
  if (start == std::string::npos) return {};
  return help.substr(start, help.find(to, start + from.size()) - start);
}

TEST(CommandLine, ConvertHelpListsEverySourceOfTheReaderTable) {
  const test::CommandResult r = run_cli("convert --help");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string description = help_part(r.output, "Convert a", "voxlines convert IN OUT.vxl");
  const std::string output_dir = help_part(r.output, "  --output-dir DIR", "  --jobs N");
  const std::string memory_limit = help_part(r.output, "  --memory-limit SIZE", "  --tsf");
  ASSERT_FALSE(output_dir.empty() || memory_limit.empty()) << r.output;
  for (const SourceFormat& f : source_formats()) {
    EXPECT_NE(description.find(f.name), std::string::npos) << f.name << " in " << description;
    for (const char* suffix : f.suffixes) {
      EXPECT_NE(description.find(suffix), std::string::npos) << suffix << " in " << description;
      EXPECT_NE(output_dir.find(suffix), std::string::npos) << suffix << " in " << output_dir;
    }
    // Each format is named as streamed, or as refused under --memory-limit.
    EXPECT_NE(memory_limit.find(f.name), std::string::npos) << f.name << " in " << memory_limit;
  }
}

}  // namespace
}  // namespace vxl
