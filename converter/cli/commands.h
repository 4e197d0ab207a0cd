// The `voxlines` subcommands. Each add_* registers its options on the app and sets a callback that does
// the work; errors are thrown as vxl::Error and turned into messages and exit codes by main().
#pragma once

#include <CLI/CLI.hpp>

namespace vxl::cli {

void add_convert_command(CLI::App& app);
void add_info_command(CLI::App& app);
void add_verify_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_synth_command(CLI::App& app);
void add_pack_command(CLI::App& app);
void add_unpack_command(CLI::App& app);

// Set by a command that wants a specific non-zero exit code without an error message (verify).
inline int g_exit_code = 0;

}  // namespace vxl::cli
