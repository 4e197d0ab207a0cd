// The output rule (format/base/output_path.h), for every writer of the converter: a FIFO, a device, a directory
// at OUT is refused (exit 5) and left as it was; a symbolic link is followed and kept; a missing folder is
// an output error.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include "format/base/error.h"
#include "format/base/output_path.h"
#include "tests/hostile_inputs.h"
#include "tests/hostile_vxl.h"
#include "tests/test_support.h"

namespace {

namespace fs = std::filesystem;
using vxl::test::q;
using vxl::test::ScratchDir;

using vxl::test::contains;

mode_t lmode(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 ? st.st_mode : 0;
}

std::string output_error(const std::string& path) {
  try {
    (void)vxl::output_target(path);
  } catch (const vxl::Error& e) {
    EXPECT_EQ(e.kind(), vxl::ErrorKind::Output) << e.what();
    return e.what();
  }
  return "no error";
}

TEST(OutputPath, OnlyRegularFilesAreReplacedAndLinksAreFollowed) {
  ScratchDir dir;
  const std::string fifo = dir.file("fifo"), folder = dir.file("folder"), file = dir.file("file");
  vxl::test::hostile::fifo(fifo);
  fs::create_directory(folder);
  vxl::test::hostile::write_file(file, "x");
  EXPECT_EQ(vxl::output_target(file), file);
  EXPECT_EQ(vxl::output_target(dir.file("new")), dir.file("new"));
  EXPECT_TRUE(contains(output_error(fifo), "fifo: is a FIFO")) << output_error(fifo);
  EXPECT_TRUE(contains(output_error(folder), "folder: is a directory")) << output_error(folder);
  EXPECT_TRUE(contains(output_error("/dev/null"), "is a character device")) << output_error("/dev/null");
  EXPECT_TRUE(contains(output_error(dir.file("missing/x.vxl")), "cannot write into the folder"));
  EXPECT_TRUE(contains(output_error(file + "/x.vxl"), "is not a folder")) << output_error(file + "/x.vxl");

  // Links: followed to what they point to, relative to their own folder, over several hops.
  fs::create_symlink("file", dir.file("to_file"));
  fs::create_symlink(dir.file("to_file"), dir.file("to_to_file"));
  fs::create_symlink("folder/new.png", dir.file("to_new"));
  fs::create_symlink("/dev/null", dir.file("to_null"));
  fs::create_symlink("fifo", dir.file("to_fifo"));
  fs::create_symlink("loop", dir.file("loop"));
  EXPECT_EQ(vxl::output_target(dir.file("to_file")), file);
  EXPECT_EQ(vxl::output_target(dir.file("to_to_file")), file);
  EXPECT_EQ(vxl::output_target(dir.file("to_new")), dir.file("folder/new.png"));
  EXPECT_TRUE(contains(output_error(dir.file("to_null")), "is a character device (where the symbolic link leads"));
  EXPECT_TRUE(contains(output_error(dir.file("to_fifo")), "is a FIFO")) << output_error(dir.file("to_fifo"));
  EXPECT_TRUE(contains(output_error(dir.file("loop")), "too many levels of symbolic links"));
}

struct Command {
  std::string args;                  // with OUT where the output goes
  std::vector<std::string> outputs;  // what OUT stands for, each tried in turn (one output at a time)
};

std::string with_out(std::string args, const std::string& out) {
  args.replace(args.find("OUT"), 3, q(out));
  return args;
}

// Every writer of `voxlines`, with OUT a FIFO, a link to /dev/null and a link to a FIFO: exit 5, all three
// left as they were, nothing written beside them; then with OUT a link to a regular file, which is
// replaced while the link stays.
TEST(OutputPath, EveryConverterWriterRefusesFifosAndDevicesAndFollowsLinks) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), vxl = dir.file("in.vxl"), vxlz = dir.file("in.vxlz");
  ASSERT_EQ(vxl::test::run_cli("synth " + q(tck) + " --streamlines 20").exit_code, 0);
  ASSERT_EQ(vxl::test::run_cli("convert " + q(tck) + " " + q(vxl)).exit_code, 0);
  ASSERT_EQ(vxl::test::run_cli("pack " + q(vxl) + " " + q(vxlz)).exit_code, 0);
  const std::vector<std::pair<std::string, std::string>> commands = {
      {"convert " + q(tck) + " OUT", ".vxl"}, {"convert " + q(tck) + " OUT --memory-limit 64M", ".vxl"},
      {"export " + q(vxl) + " OUT", ".tck"},  {"export " + q(vxl) + " OUT", ".trx"},
      {"export " + q(vxl) + " OUT", ".vtk"},  {"pack " + q(vxl) + " OUT", ".vxlz"},
      {"unpack " + q(vxlz) + " OUT", ".vxl"}, {"synth OUT --streamlines 5", ".tck"},
  };
  const std::string sub = dir.file("sub");
  fs::create_directory(sub);
  for (const auto& [args, ext] : commands) {
    SCOPED_TRACE(args + " (" + ext + ")");
    const std::string fifo = sub + "/fifo" + ext, to_null = sub + "/null" + ext, to_fifo = sub + "/to_fifo" + ext;
    vxl::test::hostile::fifo(fifo);
    fs::create_symlink("/dev/null", to_null);
    fs::create_symlink("fifo" + ext, to_fifo);
    for (const std::string& out : {fifo, to_null, to_fifo}) {
      // Under timeout: a writer that opened the FIFO would wait for a reader forever.
      const auto r = vxl::test::run_program("timeout 60", std::string(VOXLINES_CLI) + " " + with_out(args, out));
      EXPECT_EQ(r.exit_code, 5) << out << ": " << r.output;
      EXPECT_TRUE(contains(r.output, out)) << r.output;
    }
    EXPECT_TRUE(S_ISFIFO(lmode(fifo)));
    EXPECT_TRUE(S_ISLNK(lmode(to_null)));
    EXPECT_TRUE(S_ISLNK(lmode(to_fifo)));
    EXPECT_TRUE(S_ISCHR(lmode("/dev/null")));
    EXPECT_EQ(std::distance(fs::directory_iterator(sub), fs::directory_iterator()), 3) << "a temporary file left";

    const std::string real = sub + "/real" + ext, link = sub + "/link" + ext;
    vxl::test::hostile::write_file(real, "old");
    fs::create_symlink("real" + ext, link);
    const auto r = vxl::test::run_cli(with_out(args, link));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(S_ISLNK(lmode(link)));
    EXPECT_TRUE(S_ISREG(lmode(real)));
    EXPECT_GT(fs::file_size(real), 3u);
    for (const auto& e : fs::directory_iterator(sub)) fs::remove(e.path());
  }
  // A TSF beside the TCK is an output of its own.
  const std::string values = dir.file("values.vxl"), fifo = dir.file("v.tsf");
  vxl::test::VxlBytes::make(values);
  vxl::test::hostile::fifo(fifo);
  const auto r = vxl::test::run_program("timeout 60", std::string(VOXLINES_CLI) + " export " + q(values) + " " +
                                                          q(dir.file("v.tck")) + " --tsf " + q(fifo));
  EXPECT_EQ(r.exit_code, 5) << r.output;
  EXPECT_TRUE(S_ISFIFO(lmode(fifo)));
  EXPECT_FALSE(fs::exists(dir.file("v.tck")));
}

// A file under another format's name passes for that format: synth, pack and unpack name what they write, as
// convert does, and write nothing under a wrong name (any case of the right one is taken).
TEST(OutputPath, AnOutputNamedForAnotherFormatIsAUsageError) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), vxl = dir.file("in.vxl"), vxlz = dir.file("in.vxlz");
  ASSERT_EQ(vxl::test::run_cli("synth " + q(dir.file("IN.TCK")) + " --streamlines 5").exit_code, 0);
  fs::rename(dir.file("IN.TCK"), tck);
  ASSERT_EQ(vxl::test::run_cli("convert " + q(tck) + " " + q(vxl)).exit_code, 0);
  ASSERT_EQ(vxl::test::run_cli("pack " + q(vxl) + " " + q(vxlz)).exit_code, 0);
  const std::vector<std::pair<std::string, std::string>> commands = {{"synth OUT --streamlines 5", "OUT.tck"},
                                                                     {"pack " + q(vxl) + " OUT", "OUT.vxlz"},
                                                                     {"unpack " + q(vxlz) + " OUT", "OUT.vxl"},
                                                                     {"unpack " + q(vxlz) + " OUT", "OUT.vxl"}};
  const std::vector<std::string> wrong = {"s.vxl", "p.tck", "u.tck", "u.vxlz"};
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const std::string out = dir.file(wrong[i]);
    const auto r = vxl::test::run_cli(with_out(commands[i].first, out));
    EXPECT_EQ(r.exit_code, 2) << out << ": " << r.output;
    EXPECT_TRUE(contains(r.output, out)) << r.output;
    EXPECT_TRUE(contains(r.output, "name the output " + commands[i].second)) << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(OutputPath, MissingFolderOrAFolderAsOutputIsAnOutputError) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck");
  ASSERT_EQ(vxl::test::run_cli("synth " + q(tck) + " --streamlines 5").exit_code, 0);
  for (const std::string& out : {dir.file("missing/o.vxl"), dir.file("")}) {
    const auto r = vxl::test::run_cli("convert " + q(tck) + " " + q(out));
    EXPECT_EQ(r.exit_code, 5) << r.output;
  }
}

// `export X.vxl OUT.tck --tsf OUT.tck` would rename the TSF over the TCK and lose the streamlines: it is
// refused (exit 2) under any name for the same file, and nothing is written.
TEST(OutputPath, TsfOnTheTckItselfIsAUsageError) {
  ScratchDir dir;
  const std::string vxl = dir.file("values.vxl"), tck = dir.file("out.tck"), sub = dir.file("sub");
  vxl::test::VxlBytes::make(vxl);
  fs::create_directory(sub);
  fs::create_symlink("../out.tck", dir.file("sub/link.tsf"));
  const std::vector<std::string> same_names = {tck, sub + "/../out.tck", dir.file("./out.tck"),
                                               dir.file("sub/link.tsf")};
  for (const std::string& tsf : same_names) {
    SCOPED_TRACE(tsf);
    const auto r = vxl::test::run_cli("export " + q(vxl) + " " + q(tck) + " --tsf " + q(tsf));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_TRUE(contains(r.output, "is the same file as the TCK output")) << r.output;
    EXPECT_FALSE(fs::exists(tck));
  }
  // An existing TCK, and a hard link to it: kept as it was.
  vxl::test::hostile::write_file(tck, "old");
  fs::create_hard_link(tck, dir.file("hard.tsf"));
  for (const std::string& tsf : {tck, dir.file("hard.tsf"), dir.file("sub/link.tsf")}) {
    SCOPED_TRACE(tsf);
    const auto r = vxl::test::run_cli("export " + q(vxl) + " " + q(tck) + " --tsf " + q(tsf));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(fs::file_size(tck), 3u);
  }
  // Two files: both written.
  const auto r = vxl::test::run_cli("export " + q(vxl) + " " + q(tck) + " --tsf " + q(dir.file("out.tsf")));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(fs::file_size(tck), 3u);
  EXPECT_GT(fs::file_size(dir.file("out.tsf")), 0u);
}

}  // namespace
