// Read-only memory mapping of a whole file (RAII). An empty file maps to an empty span.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>

namespace vxl {

class MappedFile {
 public:
  // Maps `path` read-only; throws vxl::Error (kind Input) naming the file when it cannot.
  explicit MappedFile(const std::string& path);
  // Bytes already in memory (from std::malloc), held and freed with std::free instead of mapped: for a reader
  // that receives the file some other way (the web viewer fetches it). `name` stands for the path in errors.
  static MappedFile adopt(std::string name, std::uint8_t* malloced, std::size_t size);
  ~MappedFile();
  MappedFile(MappedFile&& other) noexcept;
  MappedFile& operator=(MappedFile&& other) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }
  std::span<const std::uint8_t> bytes() const { return {data_, size_}; }
  const std::string& path() const { return path_; }
  // From now on `name` stands for the path (in errors, and where the file is named): for a temporary file removed
  // once mapped, the file it was made from.
  void name_as(std::string name) { path_ = std::move(name); }
  // Drops the pages this process has read from its page tables: the file stays in the page cache, and a later
  // read maps them again (a minor fault). A long pass through a large file calls it now and then, so that its
  // resident size stays what it reads between calls, not the whole file.
  void release_resident_pages() const;
  // Asks the system to read bytes [offset, offset + size) into the page cache ahead of their use (a hint: nothing
  // happens for bytes in memory already or where the system declines; the reads are queued, not waited for). Reading
  // many scattered parts of a file that is not in the page cache then waits on the disk once, with the reads queued
  // together, not once a page fault.
  void will_need(std::uint64_t offset, std::uint64_t size) const;

 private:
  MappedFile() = default;
  void release();
  std::string path_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
  bool adopted_ = false;  // data_ is std::malloc's, not a mapping
};

// A mapping of bytes [offset, offset + size) of an open file, unmapped when the window is destroyed.
// Read: its pages mapped at once (MAP_POPULATE), so that a reader going through a large file a part at a
// time reads the page cache in place, without pread's copy, and adds no more than one part to its
// resident memory. Write (AtomicOutputFile::map_window): shared, what is written stays in the file's page
// cache after the window is gone. In WebAssembly a window for writing is a buffer of its own, written back
// where it lies by write_back(): Emscripten's mapping is a copy written back whole when unmapped, from the
// page boundary below the window, which would overwrite the bytes before it written meanwhile.
class FileWindow {
 public:
  enum class Access { Read, Write };
  FileWindow() = default;
  // Throws vxl::Error naming `path` when the part cannot be mapped: Input when reading, Output when writing.
  FileWindow(int fd, const std::string& path, std::uint64_t offset, std::uint64_t size, Access access = Access::Read);
  ~FileWindow();
  FileWindow(FileWindow&& other) noexcept;
  FileWindow& operator=(FileWindow&& other) noexcept;
  FileWindow(const FileWindow&) = delete;
  FileWindow& operator=(const FileWindow&) = delete;

  const std::uint8_t* data() const { return bytes_.data(); }
  std::span<std::uint8_t> bytes() const { return bytes_; }  // writable only for Access::Write

  // A window for writing: its bytes in the file now, where they are not already (WebAssembly). Throws vxl::Error
  // (Output) naming the file.
  void write_back();

 private:
  void release();
  void* map_ = nullptr;
  std::size_t map_size_ = 0;
  std::span<std::uint8_t> bytes_;
  // WebAssembly's window for writing: where its buffer (map_, malloc'd) goes back.
  int fd_ = -1;
  std::uint64_t offset_ = 0;
  std::string path_;
};

}  // namespace vxl
