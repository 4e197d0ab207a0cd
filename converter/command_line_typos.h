// Help for mistyped command lines, shared by voxlines and voxview: the nearest known name to an unknown
// subcommand or option ("unknown option --voxelsize; did you mean --voxel-size?").
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace vxl {

// The candidate closest to `word` by edit distance, when it is close enough to be a typo of it (at most a
// third of its letters, at least 2, differ); "" otherwise.
std::string nearest_name(const std::string& word, const std::vector<std::string>& candidates);

// After a parse of `argv` by `app` failed: a message naming the first unknown subcommand or option of the
// (sub)command it was given to, and the nearest known one; "" when every word is known (the parser's own
// message then says what is wrong).
std::string typo_message(const CLI::App& app, int argc, const char* const* argv);

}  // namespace vxl
