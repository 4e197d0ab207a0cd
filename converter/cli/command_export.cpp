#include <algorithm>
#include <cstdio>
#include <optional>

#include "converter/cli/commands.h"
#include "converter/export/export_groups.h"
#include "converter/export/export_tck.h"
#include "converter/export/export_trk.h"
#include "converter/export/export_trx.h"
#include "converter/export/export_vtk.h"
#include "converter/export/groups_not_written.h"
#include "converter/export/streamline_outputs.h"
#include "format/base/error.h"

namespace vxl::cli {
namespace {

void print_warnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::fprintf(stderr, "voxlines: warning: %s\n", w.c_str());
}

}  // namespace

void add_export_command(CLI::App& app) {
  struct Options {
    std::string input, output;
    TckExportSettings tck;  // --tsf, --value, --group
    std::optional<std::string> split_dir;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Write the original streamlines of a .vxl back to TCK, TRX, legacy VTK or TrackVis TRK (chosen by the output's "
      "extension)");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output,
                  "output " + streamline_output_help(true) + "; written atomically. Not with --split-groups");
  cmd->add_option("--tsf", opt->tck.tsf_path,
                  "with a .tck output: also write one per-point value set as an MRtrix TSF");
  cmd->add_option("--value", opt->tck.value,
                  "the per-point value set for --tsf (default: the first); with --split-groups, a TSF of this set "
                  "is written beside each group's TCK");
  cmd->add_option("--group", opt->tck.group, "write only the streamlines of this group");
  cmd->add_option("--split-groups", opt->split_dir,
                  "write each group to DIR/NAME.tck (the name made safe for a file name; DIR is created)");
  cmd->callback([opt] {
    if (opt->split_dir) {
      if (!opt->output.empty() || opt->tck.group || opt->tck.tsf_path)
        throw Error(ErrorKind::Usage, *opt->split_dir, std::nullopt,
                    "--split-groups writes DIR/NAME.tck (and DIR/NAME.tsf with --value SET): give no output file, "
                    "--group or --tsf with it");
      VxlFile f = VxlFile::open(opt->input);
      for (const SplitGroupFile& g : export_tck_per_group(f, *opt->split_dir, opt->tck.value)) {
        print_warnings(g.summary.warnings);
        std::printf("%s: group '%s', %llu streamlines, %llu points%s\n", g.tck.c_str(), g.group.c_str(),
                    (unsigned long long)g.summary.streamlines, (unsigned long long)g.summary.points,
                    g.tsf.empty() ? "" : (" (and " + g.tsf + ")").c_str());
      }
      return;
    }
    if (opt->output.empty()) throw Error(ErrorKind::Usage, opt->input, std::nullopt, "export needs an output file");
    const std::optional<StreamlineOutput> format = streamline_output_of(opt->output, true);
    if (!format)
      throw Error(ErrorKind::Usage, opt->output, std::nullopt,
                  "export writes " + streamline_output_suffixes(true) + " files");
    const bool tck = format == StreamlineOutput::Tck, trx = format == StreamlineOutput::Trx,
               trk = format == StreamlineOutput::Trk;
    if (!tck && (opt->tck.tsf_path || opt->tck.value))
      throw Error(ErrorKind::Usage, opt->output, std::nullopt,
                  "--tsf and --value go with a .tck output (a .trx, .vtk or .trk holds the value sets)");
    VxlFile f = VxlFile::open(opt->input);
    std::optional<StreamlineSubset> group;
    if (opt->tck.group && !tck) group.emplace(group_subset(f, *opt->tck.group));
    const SubsetCounts counts = subset_counts(f, group ? &*group : nullptr);
    if (tck) {
      const ExportSummary s = export_tck(f, opt->output, opt->tck);
      print_warnings(s.warnings);
      if (opt->tck.tsf_path) std::printf("%s: value set '%s'\n", opt->tck.tsf_path->c_str(), s.value_set.c_str());
      std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(), (unsigned long long)s.streamlines,
                  (unsigned long long)s.points);
      return;
    }
    if (trk) {
      const TrkExportSummary s = export_trk(f, opt->output, group ? &*group : nullptr);
      print_warnings(s.warnings);
      std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(), (unsigned long long)s.streamlines,
                  (unsigned long long)s.points);
      return;
    }
    if (trx) {
      export_trx(f, opt->output, group ? &*group : nullptr);
    } else {
      // Groups become 0/1 cell arrays in a VTK; their rows of values (TRX dpg) have no place there.
      if (std::optional<std::string> lost = group_values_not_written(f, "a VTK", opt->tck.group))
        print_warnings({*lost});
      export_vtk(f, opt->output, group ? &*group : nullptr);
    }
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(), (unsigned long long)counts.streamlines,
                (unsigned long long)counts.points);
  });
}

}  // namespace vxl::cli
