// An output file that appears at its path only when complete.
//
// Data is written to an unnamed file in the target directory (O_TMPFILE) and linked into place by
// commit(); a process killed at any moment leaves nothing behind. Where O_TMPFILE is unsupported it falls
// back to a hidden temporary name that is removed on failure (a SIGKILL can then leave that temporary
// file, never a partial file at the output path).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace vxl {

class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::string path);  // throws vxl::Error (Output) naming the path
  ~AtomicOutputFile();                           // discards the data unless committed
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t size);  // appends
  void write_zeros(std::size_t size);
  void pwrite(const void* data, std::size_t size, std::uint64_t offset);  // overwrites earlier bytes
  std::uint64_t position() const { return position_; }
  void commit();  // replaces any existing file at the path

  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& what) const;
  std::string path_;
  std::string temp_path_;  // empty when using O_TMPFILE
  int fd_ = -1;
  std::uint64_t position_ = 0;
  bool committed_ = false;
};

}  // namespace vxl
