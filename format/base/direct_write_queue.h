// Direct writes done on a thread of their own, for a producer that must not wait on the disk: the
// streaming conversion's placing pass fills thousands of small staging buffers (one per vertex block)
// and hands each one over when it is full, in exchange for a spare one.
//
// Why: the placing thread shares two cores with the two threads that voxelise; each synchronous write
// put it to sleep until the disk answered and then until a core was free again (0.4 ms a 128 KiB write,
// against 0.1 ms for the same writes alone), and the pass waited on it.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <mutex>
#include <vector>

#include "format/base/atomic_output.h"
#include "format/base/parallel.h"

namespace vxl {

class DirectWriteQueue {
 public:
  // `spares`: block-aligned buffers of `buffer_bytes` each, the caller's memory (it must outlive the
  // queue), handed out by submit(). `direct_fd` as for DirectRegionWriter (-1: plain pwrite).
  DirectWriteQueue(AtomicOutputFile& out, int direct_fd, std::vector<std::uint8_t*> spares, std::uint64_t buffer_bytes);
  DirectWriteQueue(const DirectWriteQueue&) = delete;
  DirectWriteQueue& operator=(const DirectWriteQueue&) = delete;
  ~DirectWriteQueue();  // waits for what is queued (a failure then goes unreported: call finish())

  std::uint64_t buffer_bytes() const { return buffer_bytes_; }

  // Queues `size` bytes at `buffer` for file offset `offset` (block-aligned), the first `skip` not written:
  // whole blocks are written directly, a partial first or last one through the page cache
  // (DirectRegionWriter::write_blocks). A buffer of
  // buffer_bytes() (`recycle`) becomes a spare once written. With `want_spare`, returns a spare, waiting
  // for one if none is free; otherwise nullptr. Rethrows an earlier failed write.
  std::uint8_t* submit(std::uint8_t* buffer, std::uint64_t size, std::uint64_t offset, std::uint64_t skip, bool recycle,
                       bool want_spare);

  // Waits until every queued write is done; rethrows the first failure.
  void finish();

 private:
  struct Job {
    std::uint8_t* buffer;
    std::uint64_t size, offset, skip;
    bool recycle;
  };
  void run();

  AtomicOutputFile& out_;
  int direct_fd_;
  std::uint64_t buffer_bytes_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> jobs_;
  std::vector<std::uint8_t*> spares_;
  std::size_t writing_ = 0;  // jobs taken by the writer and not yet done
  bool stopping_ = false;
  std::exception_ptr failure_;
  BackgroundTask<> writer_;  // last: started once the rest is set up, joined first
};

}  // namespace vxl
