// Package benchmark. For each .vxl and the TCK it was converted from, and each
// number of quantisation bits, it prints: package size (bytes per source point, ratio to the TCK), the
// share of the Draco-coded positions next to what Draco's own quantisation and prediction would take
// for the same points (the baseline the spec's predictor is measured against), the largest and RMS
// coordinate error of the unpacked file against the original (mm, over all source points) next to the
// stated bound, and the wall time of the real `voxlines pack` and `voxlines unpack` (child processes,
// median of --runs) with unpack's peak RSS.
//
// Usage: pack_bench [--bits B]... [--runs R] [--threads T] [--keep DIR] FILE.vxl SOURCE.tck [FILE.vxl SOURCE.tck]...
// Default: bits 11, 14, 16; 3 runs; all threads.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench/child_process.h"
#include "format/base/error.h"
#include "format/vxl_file.h"
#include "format/vxl_streamlines.h"
#include "format/vxlz_draco.h"
#include "format/vxlz_layout.h"
#include "format/vxlz_package.h"

namespace {

using vxl::bench::ChildRun;
using vxl::bench::run_child;

// Runs the command `runs` times; the median time and the largest peak RSS. `output` is removed before
// every run, so that each writes a new file as a user would, rather than also paying for dropping the
// previous run's file from the page cache when it replaces it.
ChildRun median_run(const std::vector<std::string>& args, const std::string& output, int runs) {
  std::vector<double> seconds;
  ChildRun worst{0, 0, 0, 0};
  for (int r = 0; r < runs; ++r) {
    std::filesystem::remove(output);
    const ChildRun c = run_child(args);
    if (c.exit_code != 0) return c;
    seconds.push_back(c.seconds);
    worst.peak_rss_kib = std::max(worst.peak_rss_kib, c.peak_rss_kib);
  }
  std::sort(seconds.begin(), seconds.end());
  worst.seconds = seconds[seconds.size() / 2];
  return worst;
}

// The 1, 5 and 15 minute load averages: timings on a shared machine mean little without them.
std::string load_average() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  double a = 0, b = 0, c = 0;
  const bool ok = f && std::fscanf(f, "%lf %lf %lf", &a, &b, &c) == 3;
  if (f) std::fclose(f);
  char text[64];
  std::snprintf(text, sizeof text, ok ? "%.2f %.2f %.2f" : "unknown", a, b, c);
  return text;
}

std::vector<float> source_points(const vxl::VxlFile& f) {
  std::vector<float> points;
  points.reserve(3 * f.meta().point_count);
  vxl::walk_streamlines(
      f, {[&](std::uint64_t, std::span<const float> xyz) { points.insert(points.end(), xyz.begin(), xyz.end()); },
          {},
          {}});
  return points;
}

// Draco's own quantisation and delta prediction, on the same points, grid and chunks as the package.
double draco_native_bytes(const std::vector<float>& points, std::uint32_t bits, const vxl::PackSection& pack) {
  const float origin[3] = {float(pack.quant_origin[0]), float(pack.quant_origin[1]), float(pack.quant_origin[2])};
  const std::size_t chunk = 3 * pack.chunk_points;
  double bytes = 0;
  for (std::size_t i = 0; i < points.size(); i += chunk) {
    const std::size_t n = std::min(chunk, points.size() - i);
    bytes += double(vxl::draco_native_size({points.data() + i, n}, bits, origin, float(pack.range)));
  }
  return bytes;
}

}  // namespace

int run(int argc, char** argv) {
  std::vector<std::uint32_t> bits;
  std::vector<std::string> files;
  std::string threads = "0", keep;
  int runs = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--bits" && i + 1 < argc)
      bits.push_back(static_cast<std::uint32_t>(std::stoul(argv[++i])));
    else if (a == "--runs" && i + 1 < argc)
      runs = std::max(1, std::stoi(argv[++i]));
    else if (a == "--threads" && i + 1 < argc)
      threads = argv[++i];
    else if (a == "--keep" && i + 1 < argc)
      keep = argv[++i];
    else if (!a.starts_with("--"))
      files.push_back(a);
    else
      files.clear(), i = argc;
  }
  if (files.empty() || files.size() % 2 != 0) {
    std::fprintf(stderr,
                 "usage: pack_bench [--bits B]... [--runs R] [--threads T] [--keep DIR] FILE.vxl SOURCE.tck [...]\n");
    return 2;
  }
  if (bits.empty()) bits = {11, 14, 16};
  const std::string cli = VOXLINES_CLI;
  const std::filesystem::path dir =
      keep.empty() ? std::filesystem::temp_directory_path() / ("voxlines_pack_bench_" + std::to_string(getpid()))
                   : std::filesystem::path(keep);
  std::filesystem::create_directories(dir);

  std::printf("machine: %u hardware threads; pack/unpack threads: %s; times are medians of %d runs; load %s\n\n",
              std::thread::hardware_concurrency(), threads.c_str(), runs, load_average().c_str());
  std::printf(
      "| data | points | bits | package MiB | bytes/point | × TCK | positions B/pt | Draco-native B/pt | max error mm "
      "| "
      "RMS error mm | bound mm | pack s | unpack s | unpack peak MiB |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  try {
    for (std::size_t f = 0; f < files.size(); f += 2) {
      const std::string& vxl = files[f];
      const double tck_bytes = double(std::filesystem::file_size(files[f + 1]));
      const vxl::VxlFile original = vxl::VxlFile::open(vxl);
      const std::vector<float> expected = source_points(original);
      const double points = double(original.meta().point_count);
      const std::string name = std::filesystem::path(vxl).stem().string();
      for (std::uint32_t b : bits) {
        const std::string package = (dir / (name + "_" + std::to_string(b) + ".vxlz")).string();
        const std::string unpacked = (dir / (name + "_" + std::to_string(b) + ".vxl")).string();
        const ChildRun pack =
            median_run({cli, "pack", vxl, package, "--bits", std::to_string(b), "--threads", threads}, package, runs);
        const ChildRun unpack = median_run({cli, "unpack", package, unpacked, "--threads", threads}, unpacked, runs);
        if (pack.exit_code != 0 || unpack.exit_code != 0) {
          std::fprintf(stderr, "pack_bench: voxlines failed on %s at %u bits (exit %d / %d)\n", vxl.c_str(), b,
                       pack.exit_code, unpack.exit_code);
          return 1;
        }
        const vxl::VxlzFile z = vxl::VxlzFile::open(package);
        double position_bytes = 0;
        for (std::uint64_t c = 0; c < z.chunk_count(); ++c)
          position_bytes += double(z.chunk(c).symbols.size() + z.chunk(c).escapes.size());
        const std::vector<float> got = source_points(vxl::VxlFile::open(unpacked));
        double max_error = 0, sum_squares = 0;
        for (std::size_t i = 0; i < std::min(got.size(), expected.size()); ++i) {
          const double e = std::abs(double(got[i]) - double(expected[i]));
          max_error = std::max(max_error, e);
          sum_squares += e * e;
        }
        const double rms = expected.empty() ? 0.0 : std::sqrt(sum_squares / double(expected.size()));
        const double native = draco_native_bytes(expected, b, z.pack());
        const double bytes = double(z.size());
        std::printf("| %s | %.0f | %u | %.2f | %.3f | %.3f | %.3f | %.3f | %.5f | %.5f | %.5f | %.2f | %.2f | %.0f |\n",
                    name.c_str(), points, b, bytes / 1048576.0, bytes / points, bytes / tck_bytes,
                    position_bytes / points, native / points, max_error, rms, z.pack().error_bound, pack.seconds,
                    unpack.seconds, double(unpack.peak_rss_kib) / 1024.0);
        std::fflush(stdout);
        if (keep.empty()) {
          std::filesystem::remove(package);
          std::filesystem::remove(unpacked);
        }
      }
    }
  } catch (const vxl::Error& e) {
    std::fprintf(stderr, "pack_bench: %s\n", e.what());
    return 1;
  }
  if (keep.empty()) std::filesystem::remove_all(dir);
  std::printf("\nload at the end: %s\n", load_average().c_str());
  return 0;
}

// A file that cannot be read is reported, not left to std::terminate.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", "pack_bench", e.what());
    return 1;
  }
}
