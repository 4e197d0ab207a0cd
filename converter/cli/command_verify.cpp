#include <cstdio>

#include "converter/cli/commands.h"
#include "format/vxl_verify.h"

namespace vxl::cli {

void add_verify_command(CLI::App& app, int& exit_code) {
  auto file = std::make_shared<std::string>();
  CLI::App* cmd =
      app.add_subcommand("verify",
                         "Check a .vxl completely: structure, every checksum, padding, orders, streamline tables.\n"
                         "Exit 0 when valid, 1 when invalid (the reason is printed).");
  cmd->add_option("file", *file, ".vxl file")->required();
  cmd->callback([file, &exit_code] {
    VerifyResult r = verify_vxl(*file);
    if (r.valid) {
      std::printf("%s: valid\n", file->c_str());
    } else {
      std::fprintf(stderr, "%s: INVALID: %s\n", file->c_str(), r.problem.c_str());
      exit_code = 1;
    }
  });
}

}  // namespace vxl::cli
