// The `voxlines` subcommands. Each add_* registers its options on the app and sets a callback that does
// the work; errors are thrown as vxl::Error and turned into messages and exit codes by main().
#pragma once

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "format/base/error.h"
#include "format/base/file_suffix.h"
#include "format/base/memory_size.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl::cli {

// Commands whose outcome is an exit code without an error message (verify: 1 for an invalid file; a
// cohort conversion: the failures' kind) set `exit_code`, which main returns.
void add_convert_command(CLI::App& app, int& exit_code);
void add_info_command(CLI::App& app);
void add_verify_command(CLI::App& app, int& exit_code);
void add_export_command(CLI::App& app);
void add_select_command(CLI::App& app);
void add_synth_command(CLI::App& app);
void add_pack_command(CLI::App& app);
void add_unpack_command(CLI::App& app);
void add_share_command(CLI::App& app);

// Refuses (exit 2, naming the file) an output whose name does not end with `suffix`, in any case: a file of one
// format under another's name passes for that one, and the reader that trusts the name fails on it. A folder is left
// to the output rule (exit 5). `what`: what the command writes and how to name it.
inline void require_output_suffix(const std::string& output, std::string_view suffix, const std::string& what) {
  if (!has_suffix_ignoring_case(output, suffix) && !std::filesystem::is_directory(output))
    throw Error(ErrorKind::Usage, output, std::nullopt, what);
}

// --positions packed|float32, shared by convert and unpack (spec §5.4). `float32_keeps`: what float32 keeps (a
// source's coordinates bit for bit; a package's, as it decodes them).
inline CLI::Option* add_positions_option(CLI::App* cmd, PositionEncoding& positions, const std::string& float32_keeps) {
  const std::map<std::string, PositionEncoding> names = {{"packed", PositionEncoding::Packed},
                                                         {"float32", PositionEncoding::Float32}};
  return cmd
      ->add_option("--positions", positions,
                   "how the .vxl stores vertex positions: packed (4 bytes a vertex, 10 bits per axis across each "
                   "voxel's bounds: within 1/2046 of the voxel's extent, about 5 um at 10 mm; `info` prints the "
                   "bound) or float32 (12 bytes, " +
                       float32_keeps + ")")
      ->type_name("packed|float32")
      ->default_str("packed")
      // The name to the encoding's number, or a message naming the two (CLI::CheckedTransformer's lists its table,
      // "{float32->0,packed->1} OR {0,1}", and takes the numbers too).
      ->transform(CLI::Validator(
          [names](std::string& name) -> std::string {
            const auto it = names.find(name);
            if (it == names.end()) return "expected packed or float32, got '" + name + "'";
            name = std::to_string(static_cast<int>(it->second));
            return {};
          },
          ""));
}

// --threads N, shared by convert, pack, unpack and share: a whole number, 0 for all cores (CLI11's own message for
// -1 is "Could not convert").
inline CLI::Option* add_threads_option(CLI::App* cmd, unsigned& threads, const std::string& help) {
  return cmd->add_option("--threads", threads, help)->default_val(0)->check([](const std::string& text) -> std::string {
    const bool digits = !text.empty() && text.size() <= 9 &&
                        std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    return digits ? "" : "expected a whole number of threads (0: all cores), got '" + text + "'";
  });
}

// --levels N, shared by convert and unpack (spec §5.12).
inline CLI::Option* add_levels_option(CLI::App* cmd, std::uint32_t& levels) {
  return cmd
      ->add_option("--levels", levels,
                   "levels of detail: level d keeps a fixed pseudo-random 1/8^d of the streamlines, with its own "
                   "orders, so that a viewer can draw a large file coarsely first (about 1/7 more order bytes); "
                   "1 writes full detail only")
      ->check(CLI::Range(1u, kMaxLevels))
      ->default_str(std::to_string(kDefaultLevels));
}

// A --memory-limit SIZE's check (convert, unpack): bytes, or KiB/MiB/GiB with K/M/G.
inline CLI::Validator memory_size_validator() {
  return CLI::Validator(
      [](std::string& s) {
        return parse_memory_size(s)
                   ? std::string()
                   : "'" + s + "' is not a memory size (a number of bytes, or of KiB/MiB/GiB with K/M/G: 512M, 2G)";
      },
      "");
}

}  // namespace vxl::cli
