#include "format/base/checksum.h"

#include <cstdio>

#include <xxhash.h>

namespace vxl {

std::uint64_t xxh3_64(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

Xxh3_64Stream::Xxh3_64Stream() : state_(XXH3_createState()) { XXH3_64bits_reset(static_cast<XXH3_state_t*>(state_)); }
Xxh3_64Stream::~Xxh3_64Stream() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }
void Xxh3_64Stream::update(const void* data, std::size_t size) {
  XXH3_64bits_update(static_cast<XXH3_state_t*>(state_), data, size);
}
std::uint64_t Xxh3_64Stream::digest() const { return XXH3_64bits_digest(static_cast<XXH3_state_t*>(state_)); }

Xxh3_128Stream::Xxh3_128Stream() : state_(XXH3_createState()) {
  XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_));
}
Xxh3_128Stream::~Xxh3_128Stream() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void Xxh3_128Stream::update(const void* data, std::size_t size) {
  XXH3_128bits_update(static_cast<XXH3_state_t*>(state_), data, size);
}

std::string Xxh3_128Stream::hex() const {
  XXH128_hash_t h = XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_));
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return buf;
}

std::string xxh3_128_hex(const void* data, std::size_t size) {
  Xxh3_128Stream s;
  s.update(data, size);
  return s.hex();
}

}  // namespace vxl
