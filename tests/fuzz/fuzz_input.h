// Our readers take paths (they memory-map files), so each fuzz input is written to a file in shared
// memory first. Any vxl::Error is an accepted outcome; anything else (a crash, a sanitizer report, another
// exception type) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <unistd.h>

namespace vxl::fuzz {

inline std::string write_input(const std::uint8_t* data, std::size_t size, const char* suffix) {
  const std::string path = "/dev/shm/voxlines_fuzz_" + std::to_string(::getpid()) + suffix;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

}  // namespace vxl::fuzz
