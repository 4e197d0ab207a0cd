#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "converter/cli/commands.h"
#include "converter/package/package_verify.h"
#include "format/base/file_suffix.h"
#include "format/vxl_verify.h"

namespace vxl::cli {

void add_verify_command(CLI::App& app, int& exit_code) {
  auto file = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "verify",
      "Check a .vxl completely: structure, every checksum, padding, orders, streamline tables; or a .vxlz package: "
      "every check of its spec, every chunk decoded, and the .vxl it unpacks to (written to $TMPDIR, else /tmp, and "
      "removed) as a .vxl.\n"
      "Exit 0 when valid, 1 when invalid (the reason is printed), 3 when the file cannot be read, 4 when it is of a "
      "version this program does not read, 5 when a package cannot be unpacked to be checked (the temporary folder).");
  cmd->add_option("file", *file, ".vxl or .vxlz file")->required();
  cmd->callback([file, &exit_code] {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*file, ec) || ::access(file->c_str(), R_OK) != 0) {
      std::fprintf(stderr, "%s: cannot be read (no such file, not a regular file, or no permission)\n", file->c_str());
      exit_code = static_cast<int>(ErrorKind::Input);
      return;
    }
    const VerifyResult r = has_suffix_ignoring_case(*file, ".vxlz") ? verify_vxlz(*file) : verify_vxl(*file);
    if (r.valid) {
      std::printf("%s: valid\n", file->c_str());
    } else if (r.kind == ErrorKind::Input) {
      std::fprintf(stderr, "%s: INVALID: %s\n", file->c_str(), r.problem.c_str());
      exit_code = 1;
    } else {
      std::fprintf(stderr, "%s: %s\n", file->c_str(), r.problem.c_str());
      exit_code = static_cast<int>(r.kind);
    }
  });
}

}  // namespace vxl::cli
