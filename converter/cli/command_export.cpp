#include <algorithm>
#include <cstdio>

#include "commands.h"
#include "error.h"
#include "export_tck.h"
#include "export_trx.h"

namespace vxl::cli {

void add_export_command(CLI::App& app) {
  struct Options {
    std::string input, output;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Write the original streamlines of a .vxl back to TCK or TRX (chosen by the output's extension)");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output,
                  "output .tck (Float32LE) or .trx (zip, stored: float32 positions, uint64 offsets, groups kept); "
                  "written atomically")
      ->required();
  cmd->callback([opt] {
    std::string lower = opt->output;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool tck = lower.ends_with(".tck"), trx = lower.ends_with(".trx");
    if (!tck && !trx) throw Error(ErrorKind::Usage, opt->output, std::nullopt, "export writes .tck or .trx files");
    VxlFile f = VxlFile::open(opt->input);
    if (!f.vertex_values().empty() || !f.streamline_values().empty())
      std::fprintf(stderr, "voxlines: warning: %s: its values per vertex / streamline (VVAL, SVAL) are not exported\n",
                   opt->input.c_str());
    if (tck) export_tck(f, opt->output);
    else export_trx(f, opt->output);
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(),
                (unsigned long long)f.meta().streamline_count, (unsigned long long)f.meta().point_count);
  });
}

}  // namespace vxl::cli
