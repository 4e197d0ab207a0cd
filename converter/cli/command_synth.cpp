#include <cstdio>

#include "converter/cli/commands.h"
#include "converter/export/tck_writer.h"
#include "converter/synth/synth.h"

namespace vxl::cli {

void add_synth_command(CLI::App& app) {
  struct Options {
    std::string output;
    SynthSettings settings;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "Generate a deterministic whole-brain-like tractogram (bundles of smooth ~1 mm-step curves) as TCK");
  cmd->add_option("output", opt->output, "output .tck")->required();
  cmd->add_option("--streamlines", opt->settings.streamlines, "number of streamlines")
      ->default_val(144000)
      ->check(CLI::Range(std::uint64_t(1), std::uint64_t(1) << 40));
  cmd->add_option("--seed", opt->settings.seed, "random seed")->default_val(1);
  cmd->callback([opt] {
    require_output_suffix(opt->output, ".tck", "synth writes a TCK file: name the output OUT.tck");
    Tractogram t = synthesize_tractogram(opt->settings);
    TckWriter w(opt->output, t.streamline_count(),
                {"voxlines_synth: streamlines=" + std::to_string(opt->settings.streamlines) +
                 " seed=" + std::to_string(opt->settings.seed)});
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add(std::span<const float>(t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])));
    w.finish();
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(), (unsigned long long)t.streamline_count(),
                (unsigned long long)t.point_count());
  });
}

}  // namespace vxl::cli
