// Our readers take paths (they memory-map files), so each fuzz input is written to a file in shared
// memory first. Any vxl::Error is an accepted outcome; anything else (a crash, a sanitizer report, another
// exception type) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <unistd.h>

#include "converter/convert/convert.h"
#include "format/base/error.h"

namespace vxl::fuzz {

inline std::string write_input(const std::uint8_t* data, std::size_t size, const char* suffix) {
  const std::string path = "/dev/shm/voxlines_fuzz_" + std::to_string(::getpid()) + suffix;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

// Reads `path` with `read` and converts whatever it accepted (on one thread): conversion must cope with
// every tractogram a reader lets through.
template <typename Read>
void read_and_convert(const std::string& path, Read read) {
  try {
    ConvertSettings s;
    s.threads = 1;
    s.memory_limit = 64u << 20;  // small buffers for small inputs; a limit does not change the bytes
    convert_tractogram(read(path), path + ".vxl", s);
  } catch (const Error&) {
  }
}

}  // namespace vxl::fuzz
