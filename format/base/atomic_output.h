// An output file that appears at its path only when complete.
//
// Data is written to an unnamed file in the target directory (O_TMPFILE) and linked into place by
// commit(); a process killed at any moment leaves nothing behind. Where O_TMPFILE is unsupported it falls
// back to a hidden temporary name that is removed on failure (a SIGKILL can then leave that temporary
// file, never a partial file at the output path).
//
// The data is either appended with write() or, when its size is known up front, filled in place through
// map(): the caller writes into memory of the file's size, which commit() writes past the page cache.
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
  ~AtomicOutputFile();  // discards the data (and any mapping) unless committed
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  void write(const void* data, std::size_t size);  // appends
  void write_zeros(std::size_t size);
  void pwrite(const void* data, std::size_t size, std::uint64_t offset);  // overwrites earlier bytes
  // Reads back `size` bytes written before, from `offset`. Throws vxl::Error (Output) when the read
  // fails or the file is shorter.
  void pread(void* data, std::size_t size, std::uint64_t offset);
  std::uint64_t position() const { return position_; }

  // Sizes the still empty file to `size` bytes and returns `size` bytes of memory, all zero, that commit()
  // writes to it (with O_DIRECT for its whole 4 KiB blocks where the file system allows it). The disk space
  // is reserved here where the file system allows it, so a full disk is an Error now rather than at
  // commit(). Call at most once, before any write(); the span stays valid until commit() or destruction.
  std::span<std::uint8_t> map(std::uint64_t size);

  // Writes the whole 4 KiB blocks inside bytes [offset, offset + size) of map()'s memory to the file now, so that
  // commit() has only the rest left to write. Those bytes must not change afterwards. May run on another thread
  // while the caller fills other bytes, but not beside another call of it or commit().
  void write_mapped_now(std::uint64_t offset, std::uint64_t size);

  // Sizes the still empty file to `size` bytes like map(), without mapping it: the caller then fills it
  // with pwrite(), or a part at a time through map_window().
  void allocate(std::uint64_t size);

  // A writable mapping of bytes [offset, offset + size) of an allocate()d file (FileWindow::Access::Write):
  // filling a part in place spares the buffer that pwrite() copies from; unmapping it when done keeps it
  // out of resident memory after.
  FileWindow map_window(std::uint64_t offset, std::uint64_t size);

  // The file opened a second time with O_DIRECT (read-write), for writes and read-backs that bypass the
  // page cache (DirectRegionWriter, VxlStreamWriter::read_back), or -1 where that is refused. Opened on
  // first call, closed by commit().
  int direct_descriptor();

  void commit();  // unmaps, then replaces any existing file at the path (where its symbolic links lead)

  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& what) const;
  void write_mapped();  // writes what write_mapped_now() has not of map()'s memory to the file
  // Writes map()'s bytes [begin, end) (begin on a block): whole blocks with O_DIRECT where allowed.
  void write_mapped_range(std::uint64_t begin, std::uint64_t end);
  void write_at(int fd, const std::uint8_t* data, std::uint64_t size, std::uint64_t offset);
  void unmap() noexcept;
  std::string path_;
  std::string target_;     // path_, or where its symbolic links lead
  std::string temp_path_;  // empty when using O_TMPFILE
  int fd_ = -1;
  int direct_fd_ = -2;  // -2: not opened yet
  std::uint64_t position_ = 0;
  std::uint8_t* map_ = nullptr;
  std::uint64_t map_size_ = 0;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> written_;  // the block ranges write_mapped_now() wrote
  bool committed_ = false;
};

// Faults in the pages of `bytes` (inside a map() mapping, a window, or fresh anonymous memory) ready for writing, in
// bulk and in address order (MADV_POPULATE_WRITE), split over up to `threads` threads, as single-page folios
// (MADV_RANDOM; see the .cpp for why). A caller that then writes scattered over the range is spared a page fault per
// first touch of a page, which is far slower. Only a hint: without kernel support (before Linux 5.14)
// or on failure, pages fault in on first touch as usual.
void prefault_for_write(std::span<std::uint8_t> bytes, unsigned threads);

}  // namespace vxl
