// `voxlines`: convert tractograms to .vxl, inspect, verify, export, pack and unpack for sharing, and
// generate synthetic data.
#include <malloc.h>

#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "converter/cli/commands.h"
#include "converter/command_line_typos.h"
#include "format/base/error.h"

namespace {

// Keep freed memory in the process instead of handing it back to the kernel. Draco allocates and
// frees several buffers of tens of bytes per point for every position chunk, and glibc would unmap them
// (above 32 MiB, or trim them from a thread's arena) and fault them in again, zeroed, for the next
// chunk: unpacking the 1M set spent 0.8 of 2.2 CPU seconds of Draco decoding in those page faults.
// Allocations above 64 MiB are still mapped on their own, and at most 256 MiB stays unreturned.
void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory();
  CLI::App app{
      "voxlines " VOXLINES_VERSION
      " — voxel-chunked tractograms for fast, correct-looking transparency.\n"
      "Exit codes: 0 ok, 1 verify found the file invalid, 2 usage, 3 bad input, 4 unsupported, 5 output error, 6 a\n"
      "cohort (--output-dir) whose files failed with different kinds of error, 70 an internal error (a bug)."};
  app.set_version_flag("--version", VOXLINES_VERSION);
  app.require_subcommand(1);
  int exit_code = 0;  // set by verify and by a cohort conversion
  vxl::cli::add_convert_command(app, exit_code);
  vxl::cli::add_info_command(app);
  vxl::cli::add_verify_command(app, exit_code);
  vxl::cli::add_export_command(app);
  vxl::cli::add_select_command(app);
  vxl::cli::add_synth_command(app);
  vxl::cli::add_pack_command(app);
  vxl::cli::add_unpack_command(app);
  vxl::cli::add_share_command(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (const std::string typo = vxl::typo_message(app, argc, argv); !typo.empty() && e.get_exit_code() != 0) {
      std::fprintf(stderr, "voxlines: error: %s\n", typo.c_str());
      return static_cast<int>(vxl::ErrorKind::Usage);
    }
    int code = app.exit(e);
    return code == 0 ? 0 : static_cast<int>(vxl::ErrorKind::Usage);
  } catch (const vxl::Error& e) {
    std::fprintf(stderr, "voxlines: error: %s\n", e.what());
    return static_cast<int>(e.kind());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "voxlines: error: out of memory\n");
    return static_cast<int>(vxl::ErrorKind::Unsupported);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "voxlines: internal error: %s\n", e.what());
    return vxl::kExitInternalError;
  }
  return exit_code;
}
