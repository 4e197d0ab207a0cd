// voxview opens a source tractogram as `voxlines convert` converts it (converter/convert/source_to_vxl.h): under a
// small --memory-limit it streams through a temporary .vxl, the scene's bytes are those of the conversion in
// memory, and no temporary file is left, also when the source is damaged.
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "format/base/error.h"
#include "tests/test_support.h"
#include "viewer/app/scene_source.h"

namespace vxl {
namespace {

using test::q;
using test::ScratchDir;

// Points $TMPDIR (the system's temporary folder for std::filesystem::temp_directory_path) at `dir` while in scope.
class TemporaryFolderAt {
 public:
  explicit TemporaryFolderAt(const std::filesystem::path& dir) {
    if (const char* old = std::getenv("TMPDIR")) old_ = old;
    std::filesystem::create_directories(dir);
    ::setenv("TMPDIR", dir.c_str(), 1);
  }
  ~TemporaryFolderAt() {
    if (old_)
      ::setenv("TMPDIR", old_->c_str(), 1);
    else
      ::unsetenv("TMPDIR");
  }

 private:
  std::optional<std::string> old_;
};

bool is_empty_folder(const std::filesystem::path& dir) { return std::filesystem::is_empty(dir); }

std::string synth_tck(const ScratchDir& dir, int streamlines) {
  const std::string tck = dir.file("s.tck");
  const test::CommandResult r = test::run_cli("synth " + q(tck) + " --streamlines " + std::to_string(streamlines));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return tck;
}

TEST(SceneSource, ASmallMemoryLimitStreamsTheSourceToTheSameBytes) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 4000);
  const test::CommandResult whole = test::run_cli("convert " + q(tck) + " " + q(dir.file("whole.vxl")));
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  ASSERT_NE(whole.output.find("memory limit 256.0 MiB"), std::string::npos) << whole.output;

  const std::filesystem::path temporary = dir.path() / "tmp";
  const TemporaryFolderAt in(temporary);
  app::SceneSourceOptions options;
  options.memory_limit = 20ull << 20;
  const app::OpenedScene streamed = app::open_scene(tck, options);
  ASSERT_TRUE(streamed.conversion);
  EXPECT_TRUE(streamed.conversion->streamed);
  EXPECT_EQ(streamed.conversion->memory_limit, options.memory_limit);
  EXPECT_GE(streamed.conversion->summary.passes, 3u);
  EXPECT_TRUE(is_empty_folder(temporary)) << "the temporary .vxl must be removed once mapped";

  const std::vector<char> expected = test::slurp(dir.file("whole.vxl"));
  ASSERT_EQ(streamed.file.bytes().size(), expected.size());
  EXPECT_TRUE(
      std::equal(expected.begin(), expected.end(), reinterpret_cast<const char*>(streamed.file.bytes().data())));

  // Without a limit (and with memory to spare) the same path converts within the default, to the same bytes.
  const app::OpenedScene in_memory = app::open_scene(tck, {});
  ASSERT_TRUE(in_memory.conversion);
  EXPECT_EQ(in_memory.conversion->memory_limit, 256ull << 20);
  EXPECT_EQ(in_memory.conversion->summary.passes, 3u);
  ASSERT_EQ(in_memory.file.bytes().size(), expected.size());
  EXPECT_TRUE(
      std::equal(expected.begin(), expected.end(), reinterpret_cast<const char*>(in_memory.file.bytes().data())));
  EXPECT_TRUE(is_empty_folder(temporary));
}

TEST(SceneSource, NoTemporaryFileIsLeftWhenTheSourceIsTruncated) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 2000);
  // Cut inside its header (a TCK cut inside its data is read up to its last whole streamline, as MRtrix does).
  std::filesystem::resize_file(tck, 20);
  const std::filesystem::path temporary = dir.path() / "tmp";
  const TemporaryFolderAt in(temporary);
  for (const std::uint64_t limit : {std::uint64_t(20) << 20, std::uint64_t(0)}) {
    SCOPED_TRACE(limit ? "streamed" : "in memory");
    app::SceneSourceOptions options;
    options.memory_limit = limit;
    try {
      (void)app::open_scene(tck, options);
      ADD_FAILURE() << "a truncated TCK was opened";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_EQ(e.file(), tck) << e.what();
    }
    EXPECT_TRUE(is_empty_folder(temporary)) << "a failed conversion left a temporary file";
  }
}

TEST(SceneSource, APackageIsUnpackedThroughATemporaryFileThatIsRemoved) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 500), vxl = dir.file("s.vxl"), vxlz = dir.file("s.vxlz");
  ASSERT_EQ(test::run_cli("convert " + q(tck) + " " + q(vxl)).exit_code, 0);
  ASSERT_EQ(test::run_cli("pack " + q(vxl) + " " + q(vxlz)).exit_code, 0);
  const std::filesystem::path temporary = dir.path() / "tmp";
  const TemporaryFolderAt in(temporary);
  app::SceneSourceOptions options;
  options.verify = true;
  const app::OpenedScene opened = app::open_scene(vxlz, options);
  EXPECT_FALSE(opened.conversion);
  EXPECT_EQ(opened.file.meta().streamline_count, 500u);
  EXPECT_TRUE(is_empty_folder(temporary));

  std::filesystem::resize_file(vxlz, std::filesystem::file_size(vxlz) / 2);
  EXPECT_THROW((void)app::open_scene(vxlz, options), Error);
  EXPECT_TRUE(is_empty_folder(temporary)) << "a damaged package left a temporary file";
}

TEST(SceneSource, VoxviewTakesTheMemoryLimitAndSaysItStreamed) {
  ScratchDir dir;
  const std::string tck = synth_tck(dir, 4000);
  const std::string temporary = dir.file("tmp");
  std::filesystem::create_directories(temporary);
  const std::string render = " --size 64x64 --render " + q(dir.file("a.png"));
  const test::CommandResult r =
      test::run_program("TMPDIR=" + q(temporary) + " " VOXVIEW_CLI, q(tck) + " --memory-limit 20M" + render);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("streamed within 20.0 MiB of memory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("To reopen it instantly, convert once:\n  voxlines convert '" + tck +
                          "' 's.vxl' "
                          "--memory-limit 20M"),
            std::string::npos)
      << r.output;
  EXPECT_TRUE(is_empty_folder(temporary));

  const test::CommandResult bad = test::run_program(VOXVIEW_CLI, q(tck) + " --memory-limit 12MB" + render);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--memory-limit '12MB' is not a memory size"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace vxl
