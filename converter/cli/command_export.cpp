#include <algorithm>
#include <cstdio>

#include "commands.h"
#include "error.h"
#include "export_tck.h"

namespace vxl::cli {

void add_export_command(CLI::App& app) {
  struct Options {
    std::string input, output;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("export", "Write the original streamlines of a .vxl back to a TCK file");
  cmd->add_option("input", opt->input, ".vxl file")->required();
  cmd->add_option("output", opt->output, "output .tck (written atomically)")->required();
  cmd->callback([opt] {
    std::string lower = opt->output;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    if (!lower.ends_with(".tck"))
      throw Error(ErrorKind::Usage, opt->output, std::nullopt, "export writes .tck files (TRX export is planned)");
    VxlFile f = VxlFile::open(opt->input);
    export_tck(f, opt->output);
    std::printf("%s: %llu streamlines, %llu points\n", opt->output.c_str(),
                (unsigned long long)f.meta().streamline_count, (unsigned long long)f.meta().point_count);
  });
}

}  // namespace vxl::cli
