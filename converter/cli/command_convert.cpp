#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "converter/cli/commands.h"
#include "converter/cli/convert_cohort.h"
#include "converter/cli/convert_file.h"
#include "converter/cli/progress_bar.h"
#include "converter/convert/convert.h"
#include "converter/convert/segment_orders.h"
#include "converter/readers/source_formats.h"
#include "converter/voxel_size_option.h"
#include "format/base/error.h"
#include "format/base/memory_size.h"

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

struct ConvertOptions {
  std::vector<std::string> files;
  std::string output_dir;
  unsigned jobs = 1;
  ConvertSettings settings;
  std::string memory_limit;
  std::string voxel_size = "10";
  bool verbose = false;
  std::vector<std::string> tsf;
};

void add_orders_option(CLI::App* cmd, std::string& orders) {
  cmd->add_option("--orders", orders,
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
}

void add_memory_limit_option(CLI::App* cmd, std::string& memory_limit) {
  cmd->add_option(
         "--memory-limit", memory_limit,
         "use at most SIZE of memory (bytes, or K/M/G: 512M, 2G): the source is read as many times and the output "
         "written in as many parts as SIZE needs, the bytes the same for any limit. " +
             source_format_names_text("/", true) + " sources only (" + source_format_names_text("/", false) +
             " are refused); a limit too small for the data is refused, naming what needs how much. Without it: 9/8 "
             "of the file's size (256 MiB to 6 GiB, at most half of the available memory; raised there where the "
             "data needs more). With --output-dir the limit is per file: --jobs N may use N times SIZE")
      ->type_name("SIZE")
      ->check(memory_size_validator());
}

// One conversion (IN OUT.vxl) or a cohort (--output-dir); returns the exit code.
int run_convert(ConvertOptions& o, bool cohort, bool jobs_given) {
  if (!o.memory_limit.empty()) o.settings.memory_limit = *parse_memory_size(o.memory_limit);
  const VoxelSizeArgument voxel_size = parse_voxel_size(o.voxel_size);
  o.settings.voxel_size = voxel_size.mm;
  o.settings.voxel_size_auto = voxel_size.automatic;
  if (cohort) {
    CohortOptions c{o.files, o.output_dir, o.jobs, o.settings, o.tsf, o.verbose};
    const int code = run_cohort(c);
    if (o.verbose) std::printf("peak resident memory: %lld KiB\n", peak_resident_kib());
    return code;
  }
  if (jobs_given) throw CLI::ValidationError("--jobs converts several files at once: it needs --output-dir DIR");
  if (o.files.size() != 2)
    throw CLI::ValidationError("convert takes IN OUT.vxl, or IN... --output-dir DIR (got " +
                               std::to_string(o.files.size()) + " file names)");
  const std::string& input = o.files[0];
  const std::string& output = o.files[1];
  require_output_suffix(
      output, ".vxl",
      "convert writes a .vxl file: name the output OUT.vxl (to write TCK, TRK, TRX or VTK from a .vxl use "
      "`voxlines export IN.vxl OUT.tck`, or `voxlines select` for some of its streamlines)");
  ProgressBar bar;
  o.settings.progress = [&bar](const char* stage, double f) { bar.update(stage, f); };
  bar.update("reading", 0.0);
  const std::string report = convert_file(input, output, o.tsf, o.settings, o.verbose, [&](const std::string& w) {
    bar.done();
    std::fprintf(stderr, "voxlines: warning: %s: %s\n", input.c_str(), w.c_str());
  });
  bar.done();
  std::fputs(report.c_str(), stdout);
  if (o.verbose) std::printf("peak resident memory: %lld KiB\n", peak_resident_kib());
  return 0;
}

}  // namespace

void add_convert_command(CLI::App& app, int& exit_code) {
  auto opt = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand(
      "convert", "Convert a " + source_format_names_text(" / ") + " tractogram (" + source_suffixes_text(", ") +
                     ") to .vxl:\n"
                     "  voxlines convert IN OUT.vxl\n"
                     "  voxlines convert IN... --output-dir DIR [--jobs N]    (a cohort: DIR/NAME.vxl for each IN)");
  cmd->add_option("files", opt->files,
                  "IN OUT.vxl: the source tractogram (" + source_descriptions_text() +
                      ") and the output (written atomically); with --output-dir: one or more sources")
      ->required();
  CLI::Option* output_dir =
      cmd->add_option(
             "--output-dir", opt->output_dir,
             "convert every input FILE into DIR/NAME.vxl (NAME: FILE's name without " + source_suffixes_text("/") +
                 "; two inputs with the same NAME are refused; DIR is created when missing). A file that fails is "
                 "reported and the others go on; a last line says how many converted and failed")
          ->type_name("DIR");
  CLI::Option* jobs =
      cmd->add_option("--jobs", opt->jobs,
                      "with --output-dir: convert N files at once, each with --threads / N worker threads (at least 1; "
                      "N is at most the number of inputs)")
          ->type_name("N")
          ->default_val(1)
          ->check(CLI::Range(1u, 4096u));
  add_voxel_size_option(*cmd, opt->voxel_size,
                        "voxel edge length in mm, or auto: chosen from the point count, extent and step length so "
                        "that voxels stay under ~32k vertices (16-bit orders), at most 10 mm; `info` shows the choice");
  add_threads_option(cmd, opt->settings.threads,
                     "worker threads in all (0: all cores); --jobs N shares them, each file getting threads / N");
  add_orders_option(cmd, opt->settings.orders);
  add_positions_option(cmd, opt->settings.positions, "the source's coordinates bit for bit");
  add_levels_option(cmd, opt->settings.levels);
  add_memory_limit_option(cmd, opt->memory_limit);
  cmd->add_option("--tsf", opt->tsf,
                  "MRtrix track scalar file with one value per point of the input (repeatable); stored so that voxview "
                  "can colour by it (--color scalar). Refused with several inputs")
      ->expected(1)
      ->take_all();
  cmd->add_flag("--verbose", opt->verbose, "print the time of each stage");
  cmd->footer(
      "Exit codes with --output-dir: 0 every file converted; otherwise the code of the failures' kind of error when "
      "they share one (3 bad input, 4 unsupported, 5 output), or 6 when files failed with different kinds. "
      "Refused before any file is read: two inputs with the same NAME, --tsf with several inputs (2), an "
      "--output-dir that cannot be created or written into (5).");
  cmd->callback([opt, output_dir, jobs, &exit_code] {
    exit_code = run_convert(*opt, output_dir->count() > 0, jobs->count() > 0);
  });
}

}  // namespace vxl::cli
