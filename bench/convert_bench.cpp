// Conversion benchmark. For `voxlines synth` sets of the given sizes, and for TCK files given as they are, it
// prints: convert wall time, CPU time (user + system) and peak RSS (the real `voxlines convert` in a child
// process, measured with wait4), output size relative to the TCK, and open time (mmap + table validation, median
// of 21). Where MRtrix's `tckinfo` is on the PATH it also times `tckinfo -count` on the same TCK (it reads every
// point), interleaved with the conversions, and prints the ratio: the yardstick for reading a file of that size.
// With --against OLD (another build's `voxlines`), each round also converts with OLD, interleaved, and the ratio
// of the two medians is printed: before and after a change in one run. MRtrix is only compared against, never
// needed.
//
// Usage: convert_bench [--streamlines N]... [--tck FILE]... [--threads T] [--rounds R] [--against OLD_VOXLINES]
//                      [--keep DIR]
// Default: 144000 and 1000000 streamlines (the paper's sizes), 3 rounds.
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

struct Options {
  std::vector<std::uint64_t> sizes;
  std::vector<std::string> tcks;
  std::string threads = "0", keep, against;
  int rounds = 3;
};

struct Medians {
  double wall = 0, cpu = 0;
  long peak_rss_kib = 0;  // the largest
};

struct Samples {
  std::vector<double> wall, cpu;
  long peak_rss_kib = 0;
  void add(const ChildRun& r) {
    wall.push_back(r.seconds);
    cpu.push_back(r.cpu_seconds);
    peak_rss_kib = std::max(peak_rss_kib, r.peak_rss_kib);
  }
  Medians medians() const { return {median(wall), median(cpu), peak_rss_kib}; }
};

// Converts `tck` with `cli` into `vxl`; false when the conversion failed.
bool convert_once(const std::string& cli, const std::string& tck, const std::string& vxl, const Options& o,
                  Samples& samples) {
  std::filesystem::remove(vxl);
  const ChildRun c = run_child({cli, "convert", tck, vxl, "--threads", o.threads});
  if (c.exit_code != 0) return false;
  samples.add(c);
  return true;
}

// One source: the rounds (tckinfo, this build, the other build), the open times, one line of results.
int measure(const std::string& label, const std::string& tck, const std::string& vxl, const std::string& tckinfo,
            const Options& o, double synth_seconds) {
  Samples now, before, counting;
  for (int r = 0; r < o.rounds; ++r) {  // the first round also warms the page cache for the TCK
    if (!tckinfo.empty()) {
      const ChildRun t = run_child({tckinfo, "-count", "-quiet", tck}, true);
      if (t.exit_code != 0) return std::fprintf(stderr, "tckinfo failed\n"), 1;
      counting.add(t);
    }
    if (!convert_once(VOXLINES_CLI, tck, vxl, o, now)) return std::fprintf(stderr, "convert failed\n"), 1;
    if (!o.against.empty() && !convert_once(o.against, tck, vxl.substr(0, vxl.size() - 4) + "-old.vxl", o, before))
      return std::fprintf(stderr, "%s convert failed\n", o.against.c_str()), 1;
  }
  std::filesystem::remove(vxl.substr(0, vxl.size() - 4) + "-old.vxl");
  std::vector<double> opens;
  std::uint64_t points = 0;
  for (int r = 0; r < 21; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    vxl::VxlFile f = vxl::VxlFile::open(vxl);
    opens.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    points = f.meta().point_count;
  }
  const double tck_mib = double(std::filesystem::file_size(tck)) / (1 << 20);
  const double vxl_mib = double(std::filesystem::file_size(vxl)) / (1 << 20);
  const Medians m = now.medians();
  std::printf("%-14s %11llu %8.2f %9.2f %7.2f %8.0f %9.1f %9.2f %8.2f", label.c_str(), (unsigned long long)points,
              synth_seconds, m.wall, m.cpu, m.peak_rss_kib / 1024.0, tck_mib, vxl_mib / tck_mib, median(opens));
  if (counting.wall.empty())
    std::printf(" %9s %9s", "-", "-");
  else
    std::printf(" %9.2f %9.2f", median(counting.wall), m.wall / median(counting.wall));
  if (o.against.empty()) {
    std::printf("\n");
  } else {
    const Medians b = before.medians();
    std::printf(" %8.2f %7.2f %8.0f %9.2f\n", b.wall, b.cpu, b.peak_rss_kib / 1024.0, m.wall / b.wall);
  }
  std::fflush(stdout);
  return 0;
}

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool value = i + 1 < argc;
    if (a == "--streamlines" && value)
      o.sizes.push_back(std::stoull(argv[++i]));
    else if (a == "--tck" && value)
      o.tcks.push_back(argv[++i]);
    else if (a == "--threads" && value)
      o.threads = argv[++i];
    else if (a == "--rounds" && value)
      o.rounds = std::max(1, std::stoi(argv[++i]));
    else if (a == "--against" && value)
      o.against = std::filesystem::absolute(argv[++i]).string();
    else if (a == "--keep" && value)
      o.keep = argv[++i];
    else
      return false;
  }
  if (o.sizes.empty() && o.tcks.empty()) o.sizes = {144000, 1000000};
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr,
                 "usage: convert_bench [--streamlines N]... [--tck FILE]... [--threads T] [--rounds R] "
                 "[--against OLD_VOXLINES] [--keep DIR]\n");
    return 2;
  }
  const std::string cli = VOXLINES_CLI;
  const std::string tckinfo = find_on_path("tckinfo");
  const std::filesystem::path dir =
      o.keep.empty() ? std::filesystem::temp_directory_path() / ("voxlines_bench_" + std::to_string(getpid()))
                     : std::filesystem::path(o.keep);
  std::filesystem::create_directories(dir);

  std::printf("machine: %u hardware threads; convert threads: %s; %d rounds, medians\n",
              std::thread::hardware_concurrency(), o.threads.c_str(), o.rounds);
  std::printf("tckinfo: %s\n", tckinfo.empty() ? "not on the PATH (no comparison)" : tckinfo.c_str());
  if (!o.against.empty()) std::printf("against: %s (interleaved)\n", o.against.c_str());
  std::printf("%-14s %11s %8s %9s %7s %8s %9s %9s %8s %9s %9s", "source", "points", "synth_s", "convert_s", "cpu_s",
              "peak_MiB", "tck_MiB", "vxl/tck", "open_ms", "tckinfo_s", "conv/tcki");
  if (!o.against.empty()) std::printf(" %8s %7s %8s %9s", "old_s", "old_cpu", "old_MiB", "new/old");
  std::printf("\n");
  for (const std::uint64_t n : o.sizes) {
    const std::string tck = (dir / ("synth_" + std::to_string(n) + ".tck")).string();
    const std::string vxl = (dir / ("synth_" + std::to_string(n) + ".vxl")).string();
    const ChildRun synth = run_child({cli, "synth", tck, "--streamlines", std::to_string(n), "--seed", "1"});
    if (synth.exit_code != 0) return std::fprintf(stderr, "synth failed\n"), 1;
    if (measure("synth " + std::to_string(n), tck, vxl, tckinfo, o, synth.seconds) != 0) return 1;
    if (o.keep.empty()) {
      std::filesystem::remove(tck);
      std::filesystem::remove(vxl);
    }
  }
  for (const std::string& tck : o.tcks) {
    const std::string vxl = (dir / (std::filesystem::path(tck).stem().string() + ".vxl")).string();
    if (measure(std::filesystem::path(tck).filename().string(), tck, vxl, tckinfo, o, 0) != 0) return 1;
    if (o.keep.empty()) std::filesystem::remove(vxl);
  }
  if (o.keep.empty()) std::filesystem::remove_all(dir);
  return 0;
}
