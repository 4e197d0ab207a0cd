#include <cstdio>

#include "converter/cli/commands.h"
#include "converter/cli/progress_bar.h"
#include "converter/package/unpack.h"

namespace vxl::cli {

void add_unpack_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    UnpackSettings settings;
    std::string memory_limit;
    bool verbose = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "unpack", "Turn a .vxlz package back into a .vxl (orders and bounds recomputed; verify accepts it)");
  cmd->add_option("input", opt->input, ".vxlz package")->required();
  cmd->add_option("output", opt->output, "output .vxl (written atomically)")->required();
  add_threads_option(cmd, opt->settings.threads, "worker threads (0: all cores)");
  add_positions_option(cmd, opt->settings.positions,
                       "the package's positions as decoded: the package quantised them, within the error bound "
                       "`pack` and `info` print");
  cmd->add_option("--levels", opt->settings.levels,
                  "levels of detail of the .vxl written (level d keeps a fixed pseudo-random 1/8^d of the "
                  "streamlines, with its own orders; 1 writes full detail only). Default: the package's own, those "
                  "of the .vxl it was packed from (5 for a package older than 2.3, which does not record them)")
      ->check(CLI::Range(1u, kMaxLevels));
  cmd->add_option("--memory-limit", opt->memory_limit,
                  "what the decoded positions may take (bytes, or K/M/G: 512M, 2G): a packed .vxl's words depend on "
                  "each voxel's bounds, known once every point is decoded, so within SIZE the positions are kept as "
                  "floats until then (12 bytes a vertex: 768 MB for 1M streamlines); past it the package is decoded "
                  "twice instead, without them: about a tenth slower, in less than half the memory. The packed words "
                  "themselves (4 bytes a vertex) are held whole within half of SIZE, else written block by block and "
                  "read back for the orders: slower again, in less memory still. The bytes are the same. Without it: "
                  "half of the available memory")
      ->type_name("SIZE")
      ->check(memory_size_validator());
  cmd->add_flag("--verbose", opt->verbose, "print the time of each stage");
  cmd->callback([opt] {
    require_output_suffix(opt->output, ".vxl", "unpack writes a .vxl file: name the output OUT.vxl");
    if (!opt->memory_limit.empty()) opt->settings.memory_limit = *parse_memory_size(opt->memory_limit);
    ProgressBar bar;
    opt->settings.progress = [&bar](const char* stage, double f) { bar.update(stage, f); };
    UnpackSummary s = unpack_vxlz(opt->input, opt->output, opt->settings);
    bar.done();
    std::printf(
        "%s: %llu streamlines, %llu points, %llu voxels; positions within %.6f mm of the packed file "
        "per axis (package %.6f mm at %u bits",
        opt->output.c_str(), (unsigned long long)s.streamlines, (unsigned long long)s.points,
        (unsigned long long)s.voxels, s.error_bound(), s.pack.error_bound, s.pack.quantization_bits);
    if (s.repack_error_bound > 0)
      std::printf(" + packed positions %.6f mm; --positions float32 writes the package's", s.repack_error_bound);
    std::printf(")\n");
    if (s.point_value_sets + s.streamline_value_sets > 0)
      std::printf("values: %u per-point and %u per-streamline set(s), exact\n", s.point_value_sets,
                  s.streamline_value_sets);
    if (opt->verbose)
      std::printf("stages: decode %.3f s (%s), orders %.3f s, write %.3f s\n", s.decode_seconds,
                  s.vertices_read_back ? "the package decoded twice, the packed words written block by block and read "
                                         "back for the orders: held whole, they would take more than half the limit"
                  : s.decoded_twice ? "the package decoded twice: its positions as floats would pass the memory limit"
                                    : "decoded once",
                  s.orders_seconds, s.write_seconds);
  });
}

}  // namespace vxl::cli
