// Sizes of memory as the command line writes them (voxlines convert --memory-limit 512M) and as the
// messages print them.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace vxl {

// "1048576", "64K", "512M", "2G" (binary units: K = 1024; the letter may be lower case) -> bytes.
// nullopt for anything else, for 0, and for sizes beyond 2^64 - 1.
std::optional<std::uint64_t> parse_memory_size(std::string_view text);

// "3.1 MiB", "12 KiB", "100 bytes".
std::string format_memory_size(std::uint64_t bytes);

// The smallest whole number of MiB not below `bytes`, as --memory-limit takes it: "37M".
std::string memory_limit_argument(std::uint64_t bytes);

}  // namespace vxl
