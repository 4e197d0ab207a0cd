#include "format/base/mapped_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <utility>

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "format/base/error.h"
#include "format/base/memory_available.h"
#include "format/base/regular_file.h"

namespace vxl {

MappedFile::MappedFile(const std::string& path) : path_(path) {
  // A FIFO is refused at once (O_NONBLOCK), not waited on.
  struct stat st {};
  const int fd = open_regular_file(path, st);
  size_ = static_cast<std::size_t>(st.st_size);
  if (size_ > 0) {
    void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      int e = errno;
      ::close(fd);
      if (e == ENOMEM)  // the file is fine; this process cannot hold it
        throw Error(ErrorKind::Unsupported, path, std::nullopt,
                    "cannot map its " + std::to_string(size_) + " bytes within " + memory_limit_text());
      fail_input(path, std::nullopt, std::string("cannot map: ") + std::strerror(e));
    }
    data_ = static_cast<const std::uint8_t*>(p);
  }
  ::close(fd);  // the mapping keeps the file alive
}

MappedFile MappedFile::adopt(std::string name, std::uint8_t* malloced, std::size_t size) {
  MappedFile f;
  f.path_ = std::move(name);
  f.data_ = malloced;
  f.size_ = size;
  f.adopted_ = true;
  return f;
}

MappedFile::~MappedFile() { release(); }

void MappedFile::release_resident_pages() const {
  // Read-only and private: nothing of ours is lost, the pages come back from the file.
  if (data_ != nullptr && !adopted_) ::madvise(const_cast<std::uint8_t*>(data_), size_, MADV_DONTNEED);
}

void MappedFile::will_need(std::uint64_t offset, std::uint64_t size) const {
  if (data_ == nullptr || adopted_ || offset >= size_) return;
  const std::uint64_t page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  const std::uint64_t end = std::min<std::uint64_t>(size_, offset + size);
  // In pieces: Linux reads at most its read-ahead window (128 KiB by default) for each call and drops the rest.
  constexpr std::uint64_t kPiece = 128 << 10;
  for (std::uint64_t at = offset / page * page; at < end; at += kPiece)
    ::madvise(const_cast<std::uint8_t*>(data_) + at, std::min(kPiece, end - at), MADV_WILLNEED);  // errors ignored
}

MappedFile::MappedFile(MappedFile&& other) noexcept
    : path_(std::move(other.path_)),
      data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)),
      adopted_(std::exchange(other.adopted_, false)) {}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
  if (this != &other) {
    release();
    path_ = std::move(other.path_);
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    adopted_ = std::exchange(other.adopted_, false);
  }
  return *this;
}

void MappedFile::release() {
  if (adopted_)
    std::free(const_cast<std::uint8_t*>(data_));
  else if (data_ != nullptr)
    ::munmap(const_cast<std::uint8_t*>(data_), size_);
  data_ = nullptr;
  size_ = 0;
  adopted_ = false;
}

#if defined(__EMSCRIPTEN__)
constexpr bool kWriteWindowsAreBuffers = true;
#else
constexpr bool kWriteWindowsAreBuffers = false;
#endif

FileWindow::FileWindow(int fd, const std::string& path, std::uint64_t offset, std::uint64_t size, Access access) {
  if (size == 0) return;
  if (kWriteWindowsAreBuffers && access == Access::Write) {
    // What a writer has not written yet reads as zeros, as in a sized output.
    map_ = size <= std::numeric_limits<std::size_t>::max() ? std::calloc(static_cast<std::size_t>(size), 1) : nullptr;
    if (map_ == nullptr)
      throw Error(ErrorKind::Output, path, std::nullopt,
                  "no memory for " + std::to_string(size) + " bytes of the output");
    map_size_ = static_cast<std::size_t>(size);
    bytes_ = {static_cast<std::uint8_t*>(map_), static_cast<std::size_t>(size)};
    fd_ = fd, offset_ = offset, path_ = path;
    return;
  }
  const std::uint64_t page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
  const std::uint64_t start = offset / page * page;
  const bool write = access == Access::Write;
  map_size_ = static_cast<std::size_t>(offset + size - start);
  void* p = ::mmap(nullptr, map_size_, write ? PROT_READ | PROT_WRITE : PROT_READ,
                   write ? MAP_SHARED : MAP_PRIVATE | MAP_POPULATE, fd, static_cast<off_t>(start));
  if (p == MAP_FAILED) {
    map_size_ = 0;
    const int e = errno;
    if (write)
      throw Error(ErrorKind::Output, path, std::nullopt,
                  std::string("cannot map part of the output: ") + std::strerror(e));
    if (e == ENOMEM)
      throw Error(ErrorKind::Unsupported, path, offset,
                  "cannot map " + std::to_string(size) + " bytes of it within " + memory_limit_text());
    fail_input(path, offset, std::string("cannot map: ") + std::strerror(e));
  }
  map_ = p;
  bytes_ = {static_cast<std::uint8_t*>(p) + (offset - start), static_cast<std::size_t>(size)};
}

FileWindow::~FileWindow() { release(); }

FileWindow::FileWindow(FileWindow&& other) noexcept
    : map_(std::exchange(other.map_, nullptr)),
      map_size_(std::exchange(other.map_size_, 0)),
      bytes_(std::exchange(other.bytes_, {})),
      fd_(std::exchange(other.fd_, -1)),
      offset_(other.offset_),
      path_(std::move(other.path_)) {}

FileWindow& FileWindow::operator=(FileWindow&& other) noexcept {
  if (this != &other) {
    release();
    map_ = std::exchange(other.map_, nullptr);
    map_size_ = std::exchange(other.map_size_, 0);
    bytes_ = std::exchange(other.bytes_, {});
    fd_ = std::exchange(other.fd_, -1);
    offset_ = other.offset_;
    path_ = std::move(other.path_);
  }
  return *this;
}

void FileWindow::write_back() {
  if (fd_ < 0) return;  // a mapping: its bytes are the file's
  for (std::size_t done = 0; done < bytes_.size();) {
    const ssize_t n = ::pwrite(fd_, bytes_.data() + done, bytes_.size() - done, static_cast<off_t>(offset_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw Error(ErrorKind::Output, path_, std::nullopt,
                  std::string("write failed: ") + (n < 0 ? std::strerror(errno) : "nothing written"));
    done += static_cast<std::size_t>(n);
  }
}

void FileWindow::release() {
  if (fd_ >= 0)
    std::free(map_);  // a buffer: written back (write_back) or given up
  else if (map_ != nullptr)
    ::munmap(map_, map_size_);
  map_ = nullptr;
  map_size_ = 0;
  bytes_ = {};
  fd_ = -1;
}

}  // namespace vxl
