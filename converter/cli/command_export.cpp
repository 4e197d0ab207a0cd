#include <algorithm>
#include <cstdio>

#include "commands.h"
#include "error.h"
#include "export_tck.h"
#include "export_trx.h"
#include "export_vtk.h"

namespace vxl::cli {

void add_export_command(CLI::App& app) {
  struct Options {
    std::string input, output;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Write the original streamlines of a .vxl back to TCK, TRX or legacy VTK (chosen by the output's extension)");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output,
                  "output .tck (Float32LE), .trx (zip, stored: float32 positions, uint64 offsets, groups kept) or .vtk "
                  "(legacy BINARY POLYDATA, values kept as POINT_DATA / CELL_DATA scalars); written atomically")
      ->required();
  cmd->callback([opt] {
    std::string lower = opt->output;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool tck = lower.ends_with(".tck"), trx = lower.ends_with(".trx"), vtk = lower.ends_with(".vtk");
    if (!tck && !trx && !vtk) throw Error(ErrorKind::Usage, opt->output, std::nullopt, "export writes .tck, .trx or .vtk files");
    VxlFile f = VxlFile::open(opt->input);
    if (!vtk && (!f.vertex_values().empty() || !f.streamline_values().empty()))
      std::fprintf(stderr, "voxlines: warning: %s: its values per vertex / streamline (VVAL, SVAL) are not exported\n",
                   opt->input.c_str());
    if (tck) export_tck(f, opt->output);
    else if (trx) export_trx(f, opt->output);
    else export_vtk(f, opt->output);
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(),
                (unsigned long long)f.meta().streamline_count, (unsigned long long)f.meta().point_count);
  });
}

}  // namespace vxl::cli
