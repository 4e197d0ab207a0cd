// Hand-made MRtrix files (TCK, TSF) for reader tests: a header with the given datatype and extra lines,
// then the raw data bytes; raw() spells values as bytes in either byte order.
#pragma once

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <string>

namespace vxl::test {

// `magic` is "mrtrix tracks" or "mrtrix track scalars". The data offset is padded to 4 digits, so the
// header's length does not depend on it.
inline void write_mrtrix_file(const std::string& path, const std::string& magic, const std::string& datatype,
                              const std::string& data, const std::string& extra = "") {
  const std::string head = magic + "\ndatatype: " + datatype + "\n" + extra + "file: . ";
  const std::string tail = "\nEND\n";
  char num[8];
  std::snprintf(num, sizeof num, "%4zu", head.size() + 4 + tail.size());
  std::ofstream(path, std::ios::binary) << head << num << tail << data;
}

template <typename T>
std::string raw(std::initializer_list<T> values, bool big_endian = false) {
  std::string s;
  for (T v : values) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big_endian) std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
  }
  return s;
}

}  // namespace vxl::test
