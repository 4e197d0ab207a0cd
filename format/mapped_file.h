// Read-only memory mapping of a whole file (RAII). An empty file maps to an empty span.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace vxl {

class MappedFile {
 public:
  // Maps `path` read-only; throws vxl::Error (kind Input) naming the file when it cannot.
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(MappedFile&& other) noexcept;
  MappedFile& operator=(MappedFile&& other) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return size_; }
  std::span<const std::uint8_t> bytes() const { return {data_, size_}; }
  const std::string& path() const { return path_; }

 private:
  void release();
  std::string path_;
  const std::uint8_t* data_ = nullptr;
  std::size_t size_ = 0;
};

// A read-only mapping of bytes [offset, offset + size) of an open file, its pages mapped at once
// (MAP_POPULATE): a reader that goes through a large file a part at a time reads the page cache in place,
// without pread's copy, and unmaps each part when it moves on, so the file never adds more than one
// part to its resident memory.
class FileWindow {
 public:
  FileWindow() = default;
  // Throws vxl::Error (Input) naming `path` when the part cannot be mapped.
  FileWindow(int fd, const std::string& path, std::uint64_t offset, std::uint64_t size);
  ~FileWindow();
  FileWindow(FileWindow&& other) noexcept;
  FileWindow& operator=(FileWindow&& other) noexcept;
  FileWindow(const FileWindow&) = delete;
  FileWindow& operator=(const FileWindow&) = delete;

  const std::uint8_t* data() const { return data_; }

 private:
  void release();
  void* map_ = nullptr;
  std::size_t map_size_ = 0;
  const std::uint8_t* data_ = nullptr;
};

}  // namespace vxl
