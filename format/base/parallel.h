// The project's one way to run a parallel loop. Every parallel loop of the converter, the package codec,
// the writer and the viewer's upload goes through parallel_for, so that they share one
// rule for the thread count (0 = all hardware threads) and one exception policy: the first exception
// thrown by any item stops the hand-out of further items and is rethrown on the caller's thread once
// every thread has joined (items already running finish; later exceptions are dropped).
//
// Threads are started per call, not kept in a pool: every call here runs for milliseconds to seconds,
// so the start-up (tens of microseconds) does not show, and nothing outlives the call. Work that overlaps
// with other work rather than splitting it — sections written while the orders are built, the next chunk
// of vertices read back, the direct-write queue — runs as a BackgroundTask owned by the object that
// needs it: the converter and the format library start no thread elsewhere.
// Lives in format/, the library every other one links, so that all of them can use it.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "format/base/error.h"

namespace vxl {

// Whether this build can start threads: a WebAssembly build without them (the web viewer's) runs every
// loop and every task on the calling thread.
#if defined(__EMSCRIPTEN__) && !defined(__EMSCRIPTEN_PTHREADS__)
inline constexpr bool kThreadsAvailable = false;
#else
inline constexpr bool kThreadsAvailable = true;
#endif

// The number of worker threads for a requested count: `requested` itself, or all hardware threads for 0
// (1 where no thread can be started).
inline unsigned resolve_threads(unsigned requested) {
  if (!kThreadsAvailable) return 1;
  if (requested > 0) return requested;
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

// Starts a thread running fn. The system refuses a thread when the address space or the memory is spent
// (each thread reserves its stack) or a process limit is reached: that is reported as running out of
// memory (exit 4), as a failed allocation is, not as an internal error.
template <typename Fn>
std::thread start_thread(Fn&& fn) {
  try {
    return std::thread(std::forward<Fn>(fn));
  } catch (const std::system_error& e) {
    throw Error(ErrorKind::Unsupported, "", std::nullopt,
                std::string("out of memory: cannot start a thread (") + e.what() + ")");
  }
}

// Calls fn(item, thread) for every item in [0, count), handing items out one at a time to
// min(resolve_threads(threads), count) threads; `thread` is in [0, that number) and names the worker, so
// that fn can keep per-thread scratch in a vector indexed by it. Thread 0 is the calling thread.
template <typename Fn>
void parallel_for(std::uint64_t count, unsigned threads, Fn&& fn) {
  const unsigned workers = static_cast<unsigned>(std::min<std::uint64_t>(resolve_threads(threads), count));
  if (workers <= 1) {
    for (std::uint64_t i = 0; i < count; ++i) fn(i, 0u);
    return;
  }
  std::atomic<std::uint64_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&](unsigned t) {
    try {
      for (std::uint64_t i; (i = next.fetch_add(1, std::memory_order_relaxed)) < count;) fn(i, t);
    } catch (...) {
      std::lock_guard lock(error_mutex);
      if (!error) error = std::current_exception();
      next = count;
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  try {
    for (unsigned t = 1; t < workers; ++t) pool.push_back(start_thread([&worker, t] { worker(t); }));
  } catch (...) {
    // The threads already started must be joined before the pool is destroyed (a joinable thread's
    // destructor ends the process); they stop at their next item.
    next = count;
    for (std::thread& th : pool) th.join();
    throw;
  }
  worker(0);
  for (std::thread& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

// Like parallel_for, but every item runs to its end and the exception rethrown is that of the lowest item
// that threw: for work cut in order (the parts of a batch of streamlines), so that the error reported is
// the first in that order, whatever the timing.
// With `order` (a permutation of [0, count), or empty for 0, 1, ...), the items are handed out in that order —
// the longest first, say, so that the threads finish together — and the exception is still the lowest item's.
template <typename Fn>
void parallel_for_first_error_in_order(std::uint64_t count, unsigned threads, Fn&& fn,
                                       std::span<const std::uint64_t> order = {}) {
  if (!order.empty() && order.size() != count)
    throw std::logic_error("parallel_for_first_error_in_order: the order is not of the items");
  std::vector<std::exception_ptr> errors(count);
  parallel_for(count, threads, [&](std::uint64_t k, unsigned t) {
    const std::uint64_t i = order.empty() ? k : order[k];
    try {
      fn(i, t);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Runs a() and b() side by side (b on the calling thread), or one after the other when `concurrent` is
// false; the exception policy is parallel_for's.
template <typename A, typename B>
void parallel_invoke(bool concurrent, A&& a, B&& b) {
  parallel_for(2, concurrent ? 2u : 1u, [&](std::uint64_t item, unsigned) {
    if (item == 0)
      a();
    else
      b();
  });
}

// Runs fn() on a thread of its own while the caller goes on; get() waits for it and returns its result
// or rethrows its exception on the caller's thread. A task not waited for is joined by its destructor
// (its exception dropped): nothing outlives the owner. An empty task (default-constructed, moved from,
// or after get()) is not valid(); ready() says, without waiting, whether get() would return at once.
template <typename T = void>
class BackgroundTask {
 public:
  BackgroundTask() = default;
  template <typename Fn>
  explicit BackgroundTask(Fn&& fn) : state_(std::make_unique<State>()) {
    if constexpr (!kThreadsAvailable) {
      run(*state_, fn);  // done before the caller goes on: get() returns at once
    } else {
      thread_ = start_thread([state = state_.get(), fn = std::forward<Fn>(fn)]() mutable { run(*state, fn); });
    }
  }
  BackgroundTask(BackgroundTask&&) noexcept = default;
  BackgroundTask& operator=(BackgroundTask&& other) noexcept {
    join();
    thread_ = std::move(other.thread_);
    state_ = std::move(other.state_);
    return *this;
  }
  ~BackgroundTask() { join(); }

  bool valid() const { return state_ != nullptr; }
  bool ready() const { return state_ && state_->finished.load(std::memory_order_acquire); }
  T get() {
    join();
    const std::unique_ptr<State> state = std::move(state_);
    if (state->error) std::rethrow_exception(state->error);
    if constexpr (!std::is_void_v<T>) return std::move(*state->value);
  }

 private:
  struct Empty {};
  struct State {
    std::conditional_t<std::is_void_v<T>, Empty, std::optional<T>> value;
    std::exception_ptr error;
    std::atomic<bool> finished{false};
  };
  template <typename Fn>
  static void run(State& state, Fn& fn) {
    try {
      if constexpr (std::is_void_v<T>)
        fn();
      else
        state.value.emplace(fn());
    } catch (...) {
      state.error = std::current_exception();
    }
    state.finished.store(true, std::memory_order_release);
  }
  void join() {
    if (thread_.joinable()) thread_.join();
  }
  std::thread thread_;
  std::unique_ptr<State> state_;  // apart from the task, so that moving the task does not move it
};

}  // namespace vxl
