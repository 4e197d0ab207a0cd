#include <algorithm>
#include <cstdio>

#include "converter/cli/commands.h"
#include "converter/export_tck.h"
#include "converter/export_trx.h"
#include "converter/export_vtk.h"
#include "format/error.h"

namespace vxl::cli {

void add_export_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    TckExportSettings tck;  // --tsf, --value
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Write the original streamlines of a .vxl back to TCK, TRX or legacy VTK (chosen by the output's extension)");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option(
         "output", opt->output,
         "output .tck (Float32LE), .trx (zip, stored: float32 positions, uint64 offsets, groups, dpv and dps kept) "
         "or .vtk (legacy BINARY POLYDATA, values kept as POINT_DATA / CELL_DATA scalars); written atomically")
      ->required();
  cmd->add_option("--tsf", opt->tck.tsf_path,
                  "with a .tck output: also write one per-point value set as an MRtrix TSF");
  cmd->add_option("--value", opt->tck.value, "the per-point value set for --tsf (default: the first)");
  cmd->callback([opt] {
    std::string lower = opt->output;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool tck = lower.ends_with(".tck"), trx = lower.ends_with(".trx"), vtk = lower.ends_with(".vtk");
    if (!tck && !trx && !vtk)
      throw Error(ErrorKind::Usage, opt->output, std::nullopt, "export writes .tck, .trx or .vtk files");
    if (!tck && (opt->tck.tsf_path || opt->tck.value))
      throw Error(ErrorKind::Usage, opt->output, std::nullopt,
                  "--tsf and --value go with a .tck output (a .trx or .vtk holds every value set)");
    VxlFile f = VxlFile::open(opt->input);
    if (tck) {
      const ExportSummary s = export_tck(f, opt->output, opt->tck);
      for (const std::string& w : s.warnings) std::fprintf(stderr, "voxlines: warning: %s\n", w.c_str());
      if (opt->tck.tsf_path) std::printf("%s: value set '%s'\n", opt->tck.tsf_path->c_str(), s.value_set.c_str());
    } else if (trx) {
      export_trx(f, opt->output);
    } else {
      export_vtk(f, opt->output);
    }
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(),
                (unsigned long long)f.meta().streamline_count, (unsigned long long)f.meta().point_count);
  });
}

}  // namespace vxl::cli
