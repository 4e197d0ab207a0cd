#include <chrono>
#include <cstdio>

#include "commands.h"
#include "convert.h"
#include "error.h"
#include "progress_bar.h"
#include "read_tractogram.h"
#include "read_tsf.h"
#include "segment_orders.h"

namespace vxl::cli {

void add_convert_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    ConvertSettings settings;
    bool verbose = false;
    std::vector<std::string> tsf;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert a TCK / TRK (.trk.gz) / TRX tractogram to .vxl");
  cmd->add_option("input", opt->input, "source tractogram (.tck, .trk, .trk.gz, .trx zip or directory)")->required();
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
    Tractogram t = read_tractogram(opt->input);
    for (const std::string& tsf : opt->tsf) attach_tsf(t, tsf);
    double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const std::string& w : t.source.warnings) {
      bar.done();
      std::fprintf(stderr, "voxlines: warning: %s: %s\n", opt->input.c_str(), w.c_str());
    }
    ConvertSummary s = convert_tractogram(std::move(t), opt->output, opt->settings);
    bar.done();
    std::printf("%s: %llu streamlines, %llu points -> %llu voxels, %llu segments (%llu points added at voxel faces)\n",
                opt->output.c_str(), (unsigned long long)s.streamlines, (unsigned long long)s.points,
                (unsigned long long)s.voxels, (unsigned long long)s.segments, (unsigned long long)s.synthetic_points);
    if (opt->verbose)
      std::printf("stages: read %.3f s, voxelise %.3f s, orders %.3f s, write %.3f s\n", read_seconds, s.voxelize_seconds,
                  s.orders_seconds, s.write_seconds);
  });
}

}  // namespace vxl::cli
