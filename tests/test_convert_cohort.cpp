// `voxlines convert IN... --output-dir DIR [--jobs N]` (converter/cli/convert_cohort.h), through the built
// CLI: the outputs are the single-file conversions' bytes, a failing file does not stop the others, the exit
// status and the last line say what happened, and what is refused is refused before any work.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "tests/test_support.h"

namespace vxl {
namespace {

using test::run_cli;
using test::ScratchDir;

std::set<std::string> names_in(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

void synth(const std::string& path, int streamlines, int seed) {
  auto r =
      run_cli("synth '" + path + "' --streamlines " + std::to_string(streamlines) + " --seed " + std::to_string(seed));
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

using vxl::test::contains;

// Three sources of two formats and a file name with dots; returns their paths.
std::vector<std::string> make_sources(const ScratchDir& dir) {
  synth(dir.file("a.tck"), 150, 1);
  synth(dir.file("sub.ject.b.tck"), 120, 2);
  synth(dir.file("c_src.tck"), 100, 3);
  auto c = run_cli("convert '" + dir.file("c_src.tck") + "' '" + dir.file("c_src.vxl") + "' --threads 1");
  EXPECT_EQ(c.exit_code, 0) << c.output;
  auto e = run_cli("export '" + dir.file("c_src.vxl") + "' '" + dir.file("c.trx") + "'");
  EXPECT_EQ(e.exit_code, 0) << e.output;
  return {dir.file("a.tck"), dir.file("sub.ject.b.tck"), dir.file("c.trx")};
}

std::string quoted(const std::vector<std::string>& paths) {
  std::string s;
  for (const std::string& p : paths) s += "'" + p + "' ";
  return s;
}

TEST(ConvertCohort, OutputsAreTheSingleFileConversionsByteForByte) {
  ScratchDir dir;
  const std::vector<std::string> inputs = make_sources(dir);
  const std::vector<std::string> names = {"a.vxl", "sub.ject.b.vxl", "c.vxl"};
  // --jobs 2 of --threads 2 gives each file one thread (recorded in the provenance): compare with --threads 1.
  // --jobs 1 keeps all threads for the file.
  for (const auto& [cohort_args, single_threads] : {std::pair<std::string, std::string>{"--jobs 2 --threads 2", "1"},
                                                    {"--jobs 1 --threads 2", "2"},
                                                    {"--jobs 3 --threads 3", "1"}}) {
    SCOPED_TRACE(cohort_args);
    const std::string out = dir.file("out");
    std::filesystem::remove_all(out);
    auto r = run_cli("convert " + quoted(inputs) + "--output-dir '" + out + "' " + cohort_args);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "3 converted, 0 failed")) << r.output;
    EXPECT_EQ(names_in(out), std::set<std::string>(names.begin(), names.end()));
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      const std::string single = dir.file("single.vxl");
      auto s = run_cli("convert '" + inputs[i] + "' '" + single + "' --threads " + single_threads);
      ASSERT_EQ(s.exit_code, 0) << s.output;
      const std::string cohort_bytes = test::slurp<std::string>(out + "/" + names[i]);
      EXPECT_FALSE(cohort_bytes.empty()) << names[i];
      EXPECT_TRUE(cohort_bytes == test::slurp<std::string>(single))
          << names[i] << " differs from the single-file conversion";
    }
  }
}

TEST(ConvertCohort, ABadInputDoesNotStopTheOthers) {
  ScratchDir dir;
  synth(dir.file("a.tck"), 150, 1);
  synth(dir.file("b.tck"), 150, 2);
  {
    std::ofstream bad(dir.file("bad.tck"), std::ios::binary);
    bad << "mrtrix tracks\nnot a header\n";
  }
  for (const char* jobs : {"1", "2"}) {
    SCOPED_TRACE(jobs);
    const std::string out = dir.file(std::string("out") + jobs);
    auto r = run_cli("convert '" + dir.file("a.tck") + "' '" + dir.file("bad.tck") + "' '" + dir.file("b.tck") +
                     "' --output-dir '" + out + "' --jobs " + jobs);
    EXPECT_EQ(r.exit_code, 3) << r.output;  // the one failure's kind: malformed input
    EXPECT_TRUE(contains(r.output, "voxlines: error: " + dir.file("bad.tck"))) << r.output;
    EXPECT_TRUE(contains(r.output, "2 converted, 1 failed (" + dir.file("bad.tck") + ")")) << r.output;
    EXPECT_EQ(names_in(out), (std::set<std::string>{"a.vxl", "b.vxl"}));  // nothing for bad, no temporary file
    auto v = run_cli("verify '" + out + "/b.vxl'");
    EXPECT_EQ(v.exit_code, 0) << v.output;
  }
}

TEST(ConvertCohort, FailuresOfDifferentKindsExitWithSix) {
  ScratchDir dir;
  synth(dir.file("a.tck"), 100, 1);
  { std::ofstream(dir.file("bad.tck")) << "garbage"; }                                 // malformed: 3
  { std::ofstream(dir.file("lines.vtu")) << "<VTKFile type=\"UnstructuredGrid\"/>"; }  // unsupported: 4
  auto r = run_cli("convert '" + dir.file("bad.tck") + "' '" + dir.file("a.tck") + "' '" + dir.file("lines.vtu") +
                   "' --output-dir '" + dir.file("out") + "' --jobs 2");
  EXPECT_EQ(r.exit_code, 6) << r.output;
  EXPECT_TRUE(contains(r.output, "1 converted, 2 failed")) << r.output;
  EXPECT_TRUE(contains(r.output, dir.file("lines.vtu") + ": unsupported file type")) << r.output;
  EXPECT_EQ(names_in(dir.file("out")), (std::set<std::string>{"a.vxl"}));

  // Every file failing with one kind: that kind's code.
  auto u = run_cli("convert '" + dir.file("lines.vtu") + "' --output-dir '" + dir.file("out2") + "'");
  EXPECT_EQ(u.exit_code, 4) << u.output;
  EXPECT_TRUE(contains(u.output, "0 converted, 1 failed")) << u.output;
}

TEST(ConvertCohort, InputsWithTheSameNameAreRefusedBeforeAnyWork) {
  ScratchDir dir;
  synth(dir.file("a.tck"), 100, 1);
  std::filesystem::create_directories(dir.file("sub"));
  synth(dir.file("sub/a.tck"), 100, 2);
  synth(dir.file("b.tck"), 100, 3);
  // Another directory, the same path twice, another extension in another case (the file need not exist:
  // the check comes before any reading), .trk.gz.
  for (const std::string& second :
       {dir.file("sub/a.tck"), dir.file("a.tck"), dir.file("sub/a.TRX"), dir.file("sub/a.trk.gz")}) {
    SCOPED_TRACE(second);
    auto r = run_cli("convert '" + dir.file("b.tck") + "' '" + dir.file("a.tck") + "' '" + second + "' --output-dir '" +
                     dir.file("out") + "'");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_TRUE(contains(r.output, second + ": would be written to " + dir.file("out") + "/a.vxl")) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("out"))) << "refused, yet the output directory was made";
  }
}
TEST(ConvertCohort, OutputDirectoryIsCreatedOrRefusedUpFront) {
  ScratchDir dir;
  synth(dir.file("a.tck"), 100, 1);
  // Missing: created, with its parents.
  auto made = run_cli("convert '" + dir.file("a.tck") + "' --output-dir '" + dir.file("new/deeper") + "'");
  EXPECT_EQ(made.exit_code, 0) << made.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir.file("new/deeper/a.vxl")));

  // A regular file, or a path through one: exit 5 naming it, nothing converted.
  { std::ofstream(dir.file("plain")) << "x"; }
  for (const std::string& target : {dir.file("plain"), dir.file("plain/sub")}) {
    SCOPED_TRACE(target);
    auto r = run_cli("convert '" + dir.file("a.tck") + "' --output-dir '" + target + "'");
    EXPECT_EQ(r.exit_code, 5) << r.output;
    EXPECT_TRUE(contains(r.output, "voxlines: error: " + target + ": ")) << r.output;
    EXPECT_FALSE(contains(r.output, "converted")) << r.output;
  }

  // Not writable (root writes anywhere: only checked for other users).
  if (::geteuid() != 0) {
    std::filesystem::create_directories(dir.file("locked"));
    ::chmod(dir.file("locked").c_str(), 0555);
    auto r = run_cli("convert '" + dir.file("a.tck") + "' --output-dir '" + dir.file("locked") + "'");
    ::chmod(dir.file("locked").c_str(), 0755);
    EXPECT_EQ(r.exit_code, 5) << r.output;
    EXPECT_TRUE(contains(r.output, "cannot write into the output directory")) << r.output;
  }
}

TEST(ConvertCohort, OptionsThatNeedTheOtherFormAreUsageErrors) {
  ScratchDir dir;
  synth(dir.file("a.tck"), 100, 1);
  synth(dir.file("b.tck"), 100, 2);
  const std::string a = "'" + dir.file("a.tck") + "' ", b = "'" + dir.file("b.tck") + "' ";
  auto jobs = run_cli("convert " + a + "'" + dir.file("a.vxl") + "' --jobs 2");
  EXPECT_EQ(jobs.exit_code, 2) << jobs.output;
  EXPECT_TRUE(contains(jobs.output, "--output-dir")) << jobs.output;
  auto three = run_cli("convert " + a + b + "'" + dir.file("c.vxl") + "'");
  EXPECT_EQ(three.exit_code, 2) << three.output;
  auto one = run_cli("convert " + a);
  EXPECT_EQ(one.exit_code, 2) << one.output;
  auto tsf = run_cli("convert " + a + b + "--output-dir '" + dir.file("out") + "' --tsf '" + dir.file("x.tsf") + "'");
  EXPECT_EQ(tsf.exit_code, 2) << tsf.output;
  EXPECT_TRUE(contains(tsf.output, "--tsf")) << tsf.output;
  auto zero = run_cli("convert " + a + "--output-dir '" + dir.file("out") + "' --jobs 0");
  EXPECT_EQ(zero.exit_code, 2) << zero.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("a.vxl")));
  auto help = run_cli("convert --help");
  EXPECT_TRUE(contains(help.output, "--jobs") && contains(help.output, "threads / N") &&
              contains(help.output, "6 when files failed with different kinds"))
      << help.output;
}

}  // namespace
}  // namespace vxl
