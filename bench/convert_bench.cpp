// Conversion benchmark. For `voxlines synth` sets of the given sizes it
// prints: convert wall time and peak RSS (the real `voxlines convert` in a child process, measured with
// wait4), output size relative to the TCK, and open time (mmap + table validation, median of 21). Where MRtrix's
// `tckinfo` is on the PATH it also times `tckinfo -count` on the same TCK (it reads every point), interleaved
// with the conversions, and prints the ratio: the yardstick for reading a file of that size. MRtrix is only
// compared against, never needed.
//
// Usage: convert_bench [--streamlines N]... [--threads T] [--keep DIR]
// Default: 144000 and 1000000 streamlines (the paper's sizes).
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench/child_process.h"
#include "format/vxl_file.h"

namespace {

using vxl::bench::ChildRun;
using vxl::bench::run_child;

// `name` found in a directory of PATH, or "" when it is not.
std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path candidate = std::filesystem::path(dirs.substr(start, end - start)) / name;
    if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return "";
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::uint64_t> sizes;
  std::string threads = "0", keep;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--streamlines" && i + 1 < argc)
      sizes.push_back(std::stoull(argv[++i]));
    else if (a == "--threads" && i + 1 < argc)
      threads = argv[++i];
    else if (a == "--keep" && i + 1 < argc)
      keep = argv[++i];
    else {
      std::fprintf(stderr, "usage: convert_bench [--streamlines N]... [--threads T] [--keep DIR]\n");
      return 2;
    }
  }
  if (sizes.empty()) sizes = {144000, 1000000};
  const std::string cli = VOXLINES_CLI;
  const std::string tckinfo = find_on_path("tckinfo");
  std::filesystem::path dir =
      keep.empty() ? std::filesystem::temp_directory_path() / ("voxlines_bench_" + std::to_string(getpid()))
                   : std::filesystem::path(keep);
  std::filesystem::create_directories(dir);

  std::printf("machine: %u hardware threads; convert threads: %s\n", std::thread::hardware_concurrency(),
              threads.c_str());
  std::printf("tckinfo: %s\n", tckinfo.empty() ? "not on the PATH (no comparison)" : tckinfo.c_str());
  std::printf("%-12s %12s %10s %10s %10s %12s %12s %10s %10s %10s %10s %10s\n", "streamlines", "points", "synth_s",
              "convert_s", "peak_MiB", "tck_MiB", "vxl_MiB", "vxl/tck", "rss/vxl", "open_ms", "tckinfo_s", "conv/tcki");
  for (std::uint64_t n : sizes) {
    std::string tck = (dir / ("synth_" + std::to_string(n) + ".tck")).string();
    std::string vxl = (dir / ("synth_" + std::to_string(n) + ".vxl")).string();
    ChildRun synth = run_child({cli, "synth", tck, "--streamlines", std::to_string(n), "--seed", "1"});
    if (synth.exit_code != 0) return std::fprintf(stderr, "synth failed\n"), 1;
    // Median of 3 conversions (the first also warms the page cache for the TCK), each after a tckinfo run.
    std::vector<double> times, tckinfo_times;
    long rss = 0;
    for (int r = 0; r < 3; ++r) {
      if (!tckinfo.empty()) {
        ChildRun t = run_child({tckinfo, "-count", "-quiet", tck}, true);
        if (t.exit_code != 0) return std::fprintf(stderr, "tckinfo failed\n"), 1;
        tckinfo_times.push_back(t.seconds);
      }
      ChildRun c = run_child({cli, "convert", tck, vxl, "--threads", threads});
      if (c.exit_code != 0) return std::fprintf(stderr, "convert failed\n"), 1;
      times.push_back(c.seconds);
      rss = std::max(rss, c.peak_rss_kib);
    }
    std::vector<double> opens;
    std::uint64_t points = 0;
    for (int r = 0; r < 21; ++r) {
      auto t0 = std::chrono::steady_clock::now();
      vxl::VxlFile f = vxl::VxlFile::open(vxl);
      opens.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      points = f.meta().point_count;
    }
    double tck_mib = double(std::filesystem::file_size(tck)) / (1 << 20);
    double vxl_mib = double(std::filesystem::file_size(vxl)) / (1 << 20);
    std::printf("%-12llu %12llu %10.2f %10.2f %10.0f %12.1f %12.1f %10.2f %10.2f %10.2f", (unsigned long long)n,
                (unsigned long long)points, synth.seconds, median(times), rss / 1024.0, tck_mib, vxl_mib,
                vxl_mib / tck_mib, rss / 1024.0 / vxl_mib, median(opens));
    if (tckinfo_times.empty())
      std::printf(" %10s %10s\n", "-", "-");
    else
      std::printf(" %10.2f %10.2f\n", median(tckinfo_times), median(times) / median(tckinfo_times));
    std::fflush(stdout);
    if (keep.empty()) {
      std::filesystem::remove(tck);
      std::filesystem::remove(vxl);
    }
  }
  if (keep.empty()) std::filesystem::remove_all(dir);
  return 0;
}
