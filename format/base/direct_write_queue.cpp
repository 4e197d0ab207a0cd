#include "format/base/direct_write_queue.h"

#include <utility>

#include "format/base/direct_region_writer.h"

namespace vxl {

DirectWriteQueue::DirectWriteQueue(AtomicOutputFile& out, int direct_fd, std::vector<std::uint8_t*> spares,
                                   std::uint64_t buffer_bytes)
    : out_(out), direct_fd_(direct_fd), buffer_bytes_(buffer_bytes), spares_(std::move(spares)) {
  writer_ = BackgroundTask<>([this] { run(); });
}

DirectWriteQueue::~DirectWriteQueue() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  // writer_'s destructor joins it: the writer drains the queue first.
}

std::uint8_t* DirectWriteQueue::submit(std::uint8_t* buffer, std::uint64_t size, std::uint64_t offset,
                                       std::uint64_t skip, bool recycle, bool want_spare) {
  std::unique_lock lock(mutex_);
  if (failure_) std::rethrow_exception(failure_);
  jobs_.push_back({buffer, size, offset, skip, recycle});
  changed_.notify_all();
  if (!want_spare) return nullptr;
  // A job queued with `recycle` comes back as a spare once written, so this wait ends.
  changed_.wait(lock, [&] { return !spares_.empty() || failure_; });
  if (failure_) std::rethrow_exception(failure_);
  std::uint8_t* spare = spares_.back();
  spares_.pop_back();
  return spare;
}

void DirectWriteQueue::finish() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return (jobs_.empty() && writing_ == 0) || failure_; });
  if (failure_) std::rethrow_exception(failure_);
}

void DirectWriteQueue::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return !jobs_.empty() || stopping_; });
    if (jobs_.empty()) return;  // stopping, and nothing left
    const Job job = jobs_.front();
    jobs_.pop_front();
    ++writing_;
    if (!failure_) {
      lock.unlock();
      std::exception_ptr failed;
      try {
        DirectRegionWriter::write_blocks(out_, direct_fd_, job.buffer, job.size, job.offset, job.skip);
      } catch (...) {
        failed = std::current_exception();
      }
      lock.lock();
      if (failed && !failure_) failure_ = failed;
    }
    --writing_;
    if (job.recycle) {
      try {
        spares_.push_back(job.buffer);
      } catch (...) {  // out of memory: fail the writes rather than the process
        if (!failure_) failure_ = std::current_exception();
      }
    }
    changed_.notify_all();
  }
}

}  // namespace vxl
