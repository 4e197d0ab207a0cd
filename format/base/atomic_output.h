// An output file that appears at its path only when complete.
//
// Data is written to an unnamed file in the target directory (O_TMPFILE) and linked into place by
// commit(); a process killed at any moment leaves nothing behind. Where O_TMPFILE is unsupported it falls
// back to a hidden temporary name that is removed on failure (a SIGKILL can then leave that temporary
// file, never a partial file at the output path).
//
// The data is appended with write(), or, when its size is known up front (allocate()), written at its offsets with
// pwrite(), through map_window(), or past the page cache through direct_descriptor().
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "format/base/mapped_file.h"

namespace vxl {

class AtomicOutputFile {
 public:
  // Throws vxl::Error (Output) naming the path, also when format/base/output_path.h's rule refuses it.
  explicit AtomicOutputFile(std::string path);
  ~AtomicOutputFile();  // discards the data unless committed
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t size);  // appends
  void write_zeros(std::size_t size);
  void pwrite(const void* data, std::size_t size, std::uint64_t offset);  // overwrites earlier bytes
  // Reads back `size` bytes written before, from `offset`. Throws vxl::Error (Output) when the read
  // fails or the file is shorter.
  void pread(void* data, std::size_t size, std::uint64_t offset);
  std::uint64_t position() const { return position_; }

  // Sizes the still empty file to `size` bytes, reserving its disk space where the file system allows it (a full
  // disk is an Error now rather than later): the caller then fills it with pwrite(), or a part at a time through
  // map_window().
  void allocate(std::uint64_t size);

  // A writable mapping of bytes [offset, offset + size) of an allocate()d file (FileWindow::Access::Write):
  // filling a part in place spares the buffer that pwrite() copies from; unmapping it when done keeps it
  // out of resident memory after.
  FileWindow map_window(std::uint64_t offset, std::uint64_t size);

  // The file opened a second time with O_DIRECT (read-write), for writes and read-backs that bypass the
  // page cache (DirectRegionWriter, VxlStreamWriter::read_back), or -1 where that is refused. Opened on
  // first call, closed by commit().
  int direct_descriptor();

  void commit();  // replaces any existing file at the path (where its symbolic links lead)

  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& what) const;
  std::string path_;
  std::string target_;     // path_, or where its symbolic links lead
  std::string temp_path_;  // empty when using O_TMPFILE
  int fd_ = -1;
  int direct_fd_ = -2;  // -2: not opened yet
  std::uint64_t position_ = 0;
  bool committed_ = false;
};

// Faults in the pages of `bytes` (inside a window, or fresh anonymous memory) ready for writing, in
// bulk and in address order (MADV_POPULATE_WRITE), split over up to `threads` threads, as single-page folios
// (MADV_RANDOM; see the .cpp for why). A caller that then writes scattered over the range is spared a page fault per
// first touch of a page, which is far slower. Only a hint: without kernel support (before Linux 5.14)
// or on failure, pages fault in on first touch as usual.
void prefault_for_write(std::span<std::uint8_t> bytes, unsigned threads);

}  // namespace vxl
