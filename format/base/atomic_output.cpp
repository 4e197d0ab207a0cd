#include "format/base/atomic_output.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "format/base/error.h"
#include "format/base/output_path.h"
#include "format/base/parallel.h"

namespace vxl {

AtomicOutputFile::AtomicOutputFile(std::string path) : path_(std::move(path)), target_(output_target(path_)) {
  std::filesystem::path p(target_);
  std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
  fd_ = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    // O_TMPFILE unsupported here: fall back to a hidden temporary name beside the output.
    std::string templ = (dir / ("." + p.filename().string() + ".partial-XXXXXX")).string();
    std::vector<char> buf(templ.begin(), templ.end());
    buf.push_back('\0');
    fd_ = ::mkstemp(buf.data());
    if (fd_ < 0) fail(std::string("cannot create a file in ") + dir.string() + ": " + std::strerror(errno));
    temp_path_ = buf.data();
    ::fchmod(fd_, 0644);
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (direct_fd_ >= 0) ::close(direct_fd_);
  if (fd_ >= 0) ::close(fd_);
  if (!committed_ && !temp_path_.empty()) ::unlink(temp_path_.c_str());
}

void AtomicOutputFile::fail(const std::string& what) const {
  throw Error(ErrorKind::Output, path_, std::nullopt, what);
}

void AtomicOutputFile::write(const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    ssize_t n = ::write(fd_, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::string("write failed: ") + std::strerror(errno));
    }
    p += n;
    size -= static_cast<std::size_t>(n);
    position_ += static_cast<std::uint64_t>(n);
  }
}

void AtomicOutputFile::write_zeros(std::size_t size) {
  static const std::uint8_t zeros[4096] = {};
  while (size > 0) {
    std::size_t n = std::min(size, sizeof zeros);
    write(zeros, n);
    size -= n;
  }
}

void AtomicOutputFile::pwrite(const void* data, std::size_t size, std::uint64_t offset) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    ssize_t n = ::pwrite(fd_, p, size, static_cast<off_t>(offset));
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::string("write failed: ") + std::strerror(errno));
    }
    p += n;
    size -= static_cast<std::size_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
}

void AtomicOutputFile::pread(void* data, std::size_t size, std::uint64_t offset) {
  auto* p = static_cast<std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::pread(fd_, p, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(std::string("read-back failed: ") + std::strerror(errno));
    if (n == 0) fail("read-back failed: the file ends at byte " + std::to_string(offset));
    p += n;
    size -= static_cast<std::size_t>(n);
    offset += static_cast<std::uint64_t>(n);
  }
}

void AtomicOutputFile::allocate(std::uint64_t size) {
  if (position_ != 0) fail("internal error: allocate() on a file already written to");
  if (size == 0) return;
    // fallocate reserves the blocks (ENOSPC surfaces here); file systems without it get a sparse file. The web
    // viewer's in-memory file system has none: sizing a file there reserves its memory.
#if defined(__EMSCRIPTEN__)
  const int reserved = ENOSYS;
#else
  const int reserved = ::fallocate(fd_, 0, 0, static_cast<off_t>(size)) == 0 ? 0 : errno;
#endif
  if (reserved != 0) {
    if (reserved != EOPNOTSUPP && reserved != ENOSYS)
      fail(std::string("cannot reserve the output size: ") + std::strerror(reserved));
    if (::ftruncate(fd_, static_cast<off_t>(size)) != 0)
      fail(std::string("cannot size the output: ") + std::strerror(errno));
  }
  position_ = size;
}

FileWindow AtomicOutputFile::map_window(std::uint64_t offset, std::uint64_t size) {
  if (offset > position_ || size > position_ - offset) fail("internal error: map_window() past the allocated size");
  return FileWindow(fd_, path_, offset, size, FileWindow::Access::Write);
}

int AtomicOutputFile::direct_descriptor() {
  if (direct_fd_ == -2) {
    const std::string proc = "/proc/self/fd/" + std::to_string(fd_);
    direct_fd_ = ::open(proc.c_str(), O_RDWR | O_DIRECT | O_CLOEXEC);
    if (direct_fd_ < 0) direct_fd_ = -1;
  }
  return direct_fd_;
}

void AtomicOutputFile::commit() {
  if (direct_fd_ >= 0) ::close(direct_fd_);
  direct_fd_ = -1;
  if (temp_path_.empty()) {
    // Link the unnamed file under a temporary name, then rename over the target (rename is atomic;
    // linkat cannot replace an existing file).
    std::filesystem::path p(target_);
    std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
    std::string proc = "/proc/self/fd/" + std::to_string(fd_);
    for (int attempt = 0;; ++attempt) {
      std::string name = (dir / ("." + p.filename().string() + ".partial-" + std::to_string(::getpid()) + "-" +
                                 std::to_string(attempt)))
                             .string();
      if (::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, name.c_str(), AT_SYMLINK_FOLLOW) == 0) {
        temp_path_ = name;
        break;
      }
      if (errno != EEXIST || attempt > 100) fail(std::string("cannot link the output: ") + std::strerror(errno));
    }
  }
  if (::close(fd_) != 0) {
    fd_ = -1;
    fail(std::string("close failed: ") + std::strerror(errno));
  }
  fd_ = -1;
  if (::rename(temp_path_.c_str(), target_.c_str()) != 0)
    fail(std::string("cannot rename into place: ") + std::strerror(errno));
  committed_ = true;
}

void prefault_for_write(std::span<std::uint8_t> bytes, unsigned threads) {
#ifdef MADV_POPULATE_WRITE
  if (bytes.empty()) return;
  const std::uintptr_t page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(bytes.data()) / page * page;
  const std::uintptr_t end = reinterpret_cast<std::uintptr_t>(bytes.data() + bytes.size());
  // Whole pages per thread, and no thread for less than 8 MiB.
  const std::uintptr_t part =
      std::max<std::uintptr_t>((end - begin) / resolve_threads(threads) / page * page + page, 8u << 20);
  auto populate = [](std::uintptr_t from, std::uintptr_t to) {
    // MADV_RANDOM first: without readahead the pages come as single-page folios. With it the kernel
    // builds large folios from free 2 MiB blocks and zeroes them, and in a VM whose host has taken those
    // blocks back (free page reporting) every first touch also faults on the host: for the 1.3 GB
    // output of the 1M synthetic set, 0.8-1 s more system time in both convert and unpack (Linux 6.18
    // guest, 2 cores). Nothing is read from the file through this mapping before it is written, so
    // losing readahead costs nothing.
    ::madvise(reinterpret_cast<void*>(from), to - from, MADV_RANDOM);
    ::madvise(reinterpret_cast<void*>(from), to - from, MADV_POPULATE_WRITE);  // hints: errors are ignored
  };
  parallel_for((end - begin + part - 1) / part, threads, [&](std::uint64_t k, unsigned) {
    const std::uintptr_t from = begin + k * part;
    populate(from, std::min(end, from + part));
  });
#else
  (void)bytes, (void)threads;
#endif
}

}  // namespace vxl
