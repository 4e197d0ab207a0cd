// Runs a program as a child process and measures it: wall time from fork to exit, peak RSS (wait4), exit
// code. Shared by the whole-program benchmarks. The child's stdout goes to /dev/null (stderr too when
// `quiet`); buffered output of the parent is flushed first so the child cannot print it again.
#pragma once

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace vxl::bench {

struct ChildRun {
  double seconds;
  long peak_rss_kib;
  int exit_code;       // -1 when the child did not exit normally
  double cpu_seconds;  // user + system
};

inline ChildRun run_child(const std::vector<std::string>& args, bool quiet = false) {
  std::fflush(stdout);
  std::fflush(stderr);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const int devnull = ::open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    if (quiet) dup2(devnull, 2);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage ru {};
  wait4(pid, &status, 0, &ru);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu =
      double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  return {s, ru.ru_maxrss, WIFEXITED(status) ? WEXITSTATUS(status) : -1, cpu};
}

}  // namespace vxl::bench
