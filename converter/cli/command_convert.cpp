#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "commands.h"
#include "convert.h"
#include "error.h"
#include "memory_size.h"
#include "progress_bar.h"
#include "read_tractogram.h"
#include "read_tsf.h"
#include "segment_orders.h"
#include "streaming_convert.h"

namespace vxl::cli {
namespace {

// This process's peak resident memory (VmHWM) in KiB, or -1 where /proc does not say. Unlike a parent's
// wait4(), it does not count what the process held before exec() (a forked copy of its parent).
long long peak_resident_kib() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.starts_with("VmHWM:")) return std::stoll(line.substr(6));
  return -1;
}

}  // namespace

void add_convert_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    ConvertSettings settings;
    std::string memory_limit;
    bool verbose = false;
    std::vector<std::string> tsf;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert a TCK / TRK (.trk.gz) / TRX / VTK / VTP tractogram to .vxl");
  cmd->add_option("input", opt->input, "source tractogram (.tck, .trk, .trk.gz, .trx zip or directory, .vtk legacy POLYDATA, .vtp XML PolyData)")->required();
  cmd->add_option("output", opt->output, "output .vxl file (written atomically)")->required();
  cmd->add_option("--voxel-size", opt->settings.voxel_size, "voxel edge length in mm")
      ->default_val(10.0)->check(CLI::PositiveNumber);
  cmd->add_option("--threads", opt->settings.threads, "worker threads (0: all cores)")->default_val(0);
  cmd->add_option("--orders", opt->settings.orders,
                  "precomputed order set: axis (6 orders), axis+diag (14), or random:N (N pseudo-random directions "
                  "per voxel, 2N orders, N in 1..64)")
      ->default_val("axis")
      ->check([](const std::string& name) -> std::string {
        try {
          parse_order_set(name);
          return {};
        } catch (const Error& e) {
          return e.reason();
        }
      });
  cmd->add_option("--memory-limit", opt->memory_limit,
                  "use at most SIZE of memory (bytes, or K/M/G: 512M, 2G): reads the source several times and writes the "
                  "output in parts, byte-identical to a conversion without the limit. TCK sources only (TRK/TRX are "
                  "refused); a limit too small for the data is refused, naming what needs how much")
      ->type_name("SIZE")
      ->check(CLI::Validator(
          [](std::string& s) {
            return parse_memory_size(s) ? std::string()
                                        : "'" + s + "' is not a memory size (a number of bytes, or of KiB/MiB/GiB with K/M/G: 512M, 2G)";
          },
          ""));
  cmd->add_option("--tsf", opt->tsf,
                  "MRtrix track scalar file with one value per point of the input (repeatable); stored so that voxview "
                  "can colour by it (--color scalar)")
      ->expected(1)->take_all();
  cmd->add_flag("--verbose", opt->verbose, "print the time of each stage");
  cmd->callback([opt] {
    ProgressBar bar;
    opt->settings.progress = [&bar](const char* stage, double f) { bar.update(stage, f); };
    bar.update("reading", 0.0);
    auto t0 = std::chrono::steady_clock::now();
    ConvertSummary s;
    double read_seconds = 0;
    if (!opt->memory_limit.empty()) {
      if (!opt->tsf.empty())
        throw Error(ErrorKind::Unsupported, opt->input, std::nullopt,
                    "--memory-limit does not carry --tsf values yet; convert without the limit");
      opt->settings.memory_limit = *parse_memory_size(opt->memory_limit);
      s = convert_streaming(opt->input, opt->output, opt->settings);
      read_seconds = s.read_seconds;
      bar.done();
      for (const std::string& w : s.warnings) std::fprintf(stderr, "voxlines: warning: %s: %s\n", opt->input.c_str(), w.c_str());
    } else {
      Tractogram t = read_tractogram(opt->input);
      for (const std::string& tsf : opt->tsf) attach_tsf(t, tsf);
      read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      for (const std::string& w : t.source.warnings) {
        bar.done();
        std::fprintf(stderr, "voxlines: warning: %s: %s\n", opt->input.c_str(), w.c_str());
      }
      s = convert_tractogram(std::move(t), opt->output, opt->settings);
      bar.done();
    }
    std::printf("%s: %llu streamlines, %llu points -> %llu voxels, %llu segments (%llu points added at voxel faces)\n",
                opt->output.c_str(), (unsigned long long)s.streamlines, (unsigned long long)s.points,
                (unsigned long long)s.voxels, (unsigned long long)s.segments, (unsigned long long)s.synthetic_points);
    if (!opt->memory_limit.empty())
      std::printf("memory limit %s: %llu passes over the source, voxels built in %llu parts\n",
                  format_memory_size(opt->settings.memory_limit).c_str(), (unsigned long long)s.passes,
                  (unsigned long long)s.partitions);
    if (opt->verbose) {
      std::printf("stages: read %.3f s, voxelise %.3f s, orders %.3f s, write %.3f s\n", read_seconds, s.voxelize_seconds,
                  s.orders_seconds, s.write_seconds);
      std::printf("peak resident memory: %lld KiB\n", peak_resident_kib());
    }
  });
}

}  // namespace vxl::cli
