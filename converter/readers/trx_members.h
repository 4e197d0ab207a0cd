// A TRX's members, the same interface over a zip archive (stored or deflated, read through libzip) and a
// plain directory of the same layout (memory-mapped), for read_trx.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/base/mapped_file.h"

namespace vxl::trx {

// One member's bytes, either copied out of the archive or memory-mapped from the directory.
class Blob {
 public:
  explicit Blob(std::vector<std::uint8_t> owned) : owned_(std::move(owned)) {}
  explicit Blob(MappedFile mapped) : mapped_(std::move(mapped)) {}
  std::span<const std::uint8_t> bytes() const {
    if (mapped_) return mapped_->bytes();
    return {owned_.data(), owned_.size()};
  }

 private:
  std::vector<std::uint8_t> owned_;
  std::optional<MappedFile> mapped_;
};

class Members {
 public:
  virtual ~Members() = default;
  // Regular-file members, by relative path with '/' separators, mapped to their index for read().
  const std::map<std::string, std::uint64_t>& names() const { return names_; }
  bool has(const std::string& name) const { return names_.count(name) != 0; }
  // The member's size as the archive's directory (or the file system) says, before reading it.
  virtual std::uint64_t declared_size(const std::string& name) const = 0;
  // The member's bytes. Refuses, naming the member, one that declares or holds more than `max_bytes`:
  // `why` says where that bound comes from (header.json's counts fix every member's size), and no more
  // than max_bytes + 1 are ever inflated.
  virtual Blob read(const std::string& name, std::uint64_t max_bytes, const std::string& why) const = 0;

 protected:
  std::map<std::string, std::uint64_t> names_;
};

// The members of the zip archive at `path`, whose bytes `bytes` (the caller's mapping) must outlive them.
std::unique_ptr<Members> zip_members(const std::string& path, std::span<const std::uint8_t> bytes);
// The regular files under the directory `path`.
std::unique_ptr<Members> dir_members(const std::string& path);

}  // namespace vxl::trx
