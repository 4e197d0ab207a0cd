// A minimal work-sharing loop for the package codec: fn(i, thread) for i in [0, count), items handed out
// one at a time (they are large: chunks of points, pieces of an array). The first exception stops the
// other threads and is rethrown on the caller's thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace vxl {

template <typename Fn>
void parallel_for(std::uint64_t count, unsigned threads, Fn&& fn) {
  std::atomic<std::uint64_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&](unsigned t) {
    try {
      for (std::uint64_t i; (i = next++) < count;) fn(i, t);
    } catch (...) {
      std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      next = count;
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace vxl
