// Helpers shared by the tests: where the real fixtures are, scratch directories, running the CLI.
#pragma once

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace vxl::test {

// Whether `part` occurs in `s` (a message, an output).
inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

inline constexpr std::uint64_t kMiB = 1ull << 20;

// The bytes of a file, in one read (a character at a time took a third of some tests' time under the
// sanitizers). Throws when it cannot be opened or read, so that two missing files never compare equal.
template <typename Bytes = std::vector<char>>
Bytes slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot open " + path);
  Bytes bytes(static_cast<std::size_t>(in.tellg()), 0);
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw std::runtime_error("cannot read " + path);
  return bytes;
}

// Writes `bytes` to `path`, replacing it.
inline void write_file(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Whether one of `warnings` (a reader's or a command's) contains `part`.
inline bool has_warning(const std::vector<std::string>& warnings, const std::string& part) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [&](const std::string& w) { return w.find(part) != std::string::npos; });
}

// The real-world fixtures (../shared/data/real). A user's clone does not have them: tests that need
// them call this first and are skipped with a clear message.
inline std::filesystem::path real_data_dir() { return VOXLINES_REAL_DATA_DIR; }
inline bool have_real_data() { return std::filesystem::is_directory(real_data_dir()); }
#define VXL_REQUIRE_REAL_DATA()                                                              \
  do {                                                                                       \
    if (!::vxl::test::have_real_data())                                                      \
      GTEST_SKIP() << "real fixtures not found at " << ::vxl::test::real_data_dir()          \
                   << " (they live in ../shared/data/real beside the project; CI has them)"; \
  } while (0)
inline std::string real(const std::string& name) { return (real_data_dir() / name).string(); }

// A fresh scratch directory per test, removed at the end.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info ? info->test_suite_name() : "t") + "_" + (info ? info->name() : "x");
    for (char& c : name)
      if (c == '/') c = '_';
    path_ = std::filesystem::temp_directory_path() / ("voxlines_test_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct CommandResult {
  int exit_code;
  std::string output;  // stdout and stderr together
};

// Runs a program with the given argument string (shell syntax), capturing stdout and stderr.
inline CommandResult run_program(const std::string& program, const std::string& args) {
  std::string cmd = program + " " + args + " 2>&1";
  CommandResult r{-1, {}};
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.output.append(buf, n);
  int status = ::pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

// `s` in single quotes, for a shell command line.
inline std::string q(const std::string& s) { return "'" + s + "'"; }

// Runs the `voxlines` CLI.
inline CommandResult run_cli(const std::string& args) { return run_program(VOXLINES_CLI, args); }

// Starts `voxlines convert ARGS...` `runs` times and SIGKILLs run r once it has its output open for
// writing and r milliseconds more have passed: a kill while the output is being written, whatever the
// machine's speed. (The output is an O_TMPFILE without a name until it is complete, so the open file is
// looked for among the process's descriptors, /proc/PID/fd.) Every killed run must leave nothing at `out`
// (or, when the kill came after the rename, a complete file that `verify` accepts), and the directory
// nothing but `in.tck` and `out.vxl` (no temporary file). Returns how many runs were killed while writing.
inline int kill_conversions(const ScratchDir& dir, const std::vector<std::string>& convert_args, const std::string& out,
                            int runs) {
  std::vector<std::string> args = {VOXLINES_CLI, "convert"};
  args.insert(args.end(), convert_args.begin(), convert_args.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  auto expected_file = [](const std::filesystem::path& p) {
    return p.filename() == "in.tck" || p.filename() == "out.vxl";
  };
  // Whether process `pid` has a file of `dir` other than the input open: its output in the making.
  const std::string dir_prefix = std::filesystem::path(dir.path()).string() + "/";
  auto writing = [&](pid_t pid) {
    std::error_code ec;
    for (const auto& fd : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
      const std::string target = std::filesystem::read_symlink(fd.path(), ec).string();
      if (!ec && target.starts_with(dir_prefix) && !target.ends_with("/in.tck")) return true;
    }
    return false;
  };
  int killed_while_writing = 0;
  for (int r = 0; r < runs; ++r) {
    pid_t pid = fork();
    if (pid == 0) {
      execv(VOXLINES_CLI, argv.data());
      _exit(127);
    }
    int status = 0;
    bool exited = false;
    while (!(exited = waitpid(pid, &status, WNOHANG) == pid) && !writing(pid))
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::milliseconds(r));
      const bool was_writing = writing(pid);
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      if (WIFSIGNALED(status) && was_writing) ++killed_while_writing;
    }
    if (WIFSIGNALED(status) && std::filesystem::exists(out)) {
      EXPECT_EQ(run_program(VOXLINES_CLI, "verify '" + out + "'").exit_code, 0)
          << "run " << r << ": a killed run left an incomplete output";
    }
    std::filesystem::remove(out);
    for (const auto& e : std::filesystem::directory_iterator(dir.path()))
      EXPECT_TRUE(expected_file(e.path())) << "run " << r << " left behind: " << e.path();
  }
  return killed_while_writing;
}

}  // namespace vxl::test
