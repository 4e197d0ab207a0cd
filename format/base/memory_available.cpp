#include "format/base/memory_available.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <sys/resource.h>

#include "format/base/error.h"
#include "format/base/memory_size.h"

namespace vxl {
namespace {

// The first whole number in a file (e.g. "max" gives nullopt).
std::optional<std::uint64_t> read_number(const char* path) {
  std::ifstream in(path);
  std::uint64_t v = 0;
  if (in >> v) return v;
  return std::nullopt;
}

// A value of /proc/meminfo in bytes ("MemAvailable:   12345 kB").
std::optional<std::uint64_t> meminfo(const std::string& key) {
  std::ifstream in("/proc/meminfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream fields(line.substr(key.size() + 1));
      std::uint64_t kib = 0;
      if (fields >> kib) return kib * 1024;
    }
  return std::nullopt;
}

std::optional<std::uint64_t> cgroup_headroom() {
  for (auto [limit_path, usage_path] :
       {std::pair{"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"},
        std::pair{"/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"}}) {
    const auto limit = read_number(limit_path), usage = read_number(usage_path);
    // v1 reports "no limit" as a number near 2^63.
    if (limit && usage && *limit < (1ull << 60)) return *limit > *usage ? *limit - *usage : 0;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::uint64_t> available_memory() {
  if (const char* text = std::getenv("VOXLINES_MEMORY_AVAILABLE")) {
    const std::optional<std::uint64_t> given = parse_memory_size(text);
    // Set but not a size: a mistake to say, not a reason to fall back to a guess silently.
    if (!given)
      throw Error(ErrorKind::Usage, std::string("VOXLINES_MEMORY_AVAILABLE=") + text, std::nullopt,
                  "is not a memory size (bytes, or K/M/G: 512M, 2G)");
    return given;
  }
  std::optional<std::uint64_t> available = meminfo("MemAvailable");
  if (const auto headroom = cgroup_headroom()) available = available ? std::min(*available, *headroom) : *headroom;
  return available;
}

std::string memory_limit_text() {
  auto gib = [](std::uint64_t bytes) {
    std::ostringstream text;
    text.precision(1);
    text << std::fixed << double(bytes) / double(1ull << 30) << " GiB";
    return text.str();
  };
  rlimit address_space{};
  if (::getrlimit(RLIMIT_AS, &address_space) == 0 && address_space.rlim_cur != RLIM_INFINITY)
    return "the address-space limit (ulimit -v) of " + gib(address_space.rlim_cur);
  if (const auto available = available_memory()) return "the " + gib(*available) + " of memory available";
  return "this machine's memory";
}

}  // namespace vxl
