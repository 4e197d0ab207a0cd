// Checksums used by the .vxl format (spec §1): XXH3-64 for sections, XXH3-128 for source provenance.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace vxl {

std::uint64_t xxh3_64(const void* data, std::size_t size);

// Incremental XXH3-64: the same value as xxh3_64() over the concatenation of the updates.
class Xxh3_64Stream {
 public:
  Xxh3_64Stream();
  ~Xxh3_64Stream();
  Xxh3_64Stream(const Xxh3_64Stream&) = delete;
  Xxh3_64Stream& operator=(const Xxh3_64Stream&) = delete;
  void update(const void* data, std::size_t size);
  std::uint64_t digest() const;

 private:
  void* state_;
};

// Incremental XXH3-128, for hashing a source file (or a TRX directory's members) piece by piece.
class Xxh3_128Stream {
 public:
  Xxh3_128Stream();
  ~Xxh3_128Stream();
  Xxh3_128Stream(const Xxh3_128Stream&) = delete;
  Xxh3_128Stream& operator=(const Xxh3_128Stream&) = delete;
  void update(const void* data, std::size_t size);
  std::string hex() const;  // 32 lowercase hex digits, high half first

 private:
  void* state_;
};

std::string xxh3_128_hex(const void* data, std::size_t size);

}  // namespace vxl
