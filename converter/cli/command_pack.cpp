#include <cstdio>

#include "converter/cli/commands.h"
#include "converter/package/pack.h"
#include "format/vxl_file.h"

namespace vxl::cli {

void add_pack_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    PackSettings settings;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd =
      app.add_subcommand("pack",
                         "Compress a .vxl into a .vxlz package for sharing: tables exact, positions quantised\n"
                         "(error at most half a quantum of range / (2^bits - 1)) and Draco-coded, value sets exact;\n"
                         "a file with levels of detail ships its coarsest level first, so that a viewer receiving\n"
                         "the package can show it before the rest (spec/vxlz-package-v2.md)");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output, "output .vxlz package (written atomically)")->required();
  cmd->add_option("--bits", opt->settings.bits, "quantisation bits per coordinate over the data's bounding cube")
      ->default_val(kVxlzDefaultBits)
      ->check(CLI::Range(kVxlzMinBits, kVxlzMaxBits));
  add_threads_option(cmd, opt->settings.threads, "worker threads (0: all cores)");
  cmd->callback([opt] {
    require_output_suffix(opt->output, ".vxlz", "pack writes a .vxlz package: name the output OUT.vxlz");
    VxlFile f = VxlFile::open(opt->input);
    PackSummary s = pack_vxl(f, opt->output, opt->settings);
    const double per_point = s.points > 0 ? double(s.bytes) / double(s.points) : 0.0;
    std::printf("%s: %llu streamlines, %llu points -> %llu bytes (%.3f bytes per point, %.3fx the .vxl)\n",
                opt->output.c_str(), (unsigned long long)s.streamlines, (unsigned long long)s.points,
                (unsigned long long)s.bytes, per_point, double(s.bytes) / double(f.bytes().size()));
    std::printf(
        "positions: %u bits over a %.3f mm cube, quantum %.6f mm; error bound %.6f mm, measured max %.6f mm, RMS %.6f "
        "mm\n",
        s.pack.quantization_bits, s.pack.range, s.pack.quantum, s.pack.error_bound, s.pack.max_error, s.pack.rms_error);
    if (s.pack.level_count > 1)
      std::printf("points shipped level by level: the coarsest of the %u levels first\n", s.pack.level_count);
    if (s.point_value_sets + s.streamline_value_sets > 0)
      std::printf("values: %u per-point and %u per-streamline set(s), exact\n", s.point_value_sets,
                  s.streamline_value_sets);
  });
}

}  // namespace vxl::cli
