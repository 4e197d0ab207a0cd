#include "viewer/app/focus_copy_worker.h"

#include <chrono>
#include <exception>

#if defined(__linux__)
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace vxl::app {

void FocusCopyWorker::request(std::uint64_t generation, std::vector<std::vector<std::uint64_t>> kept) {
  if (running_.valid())
    waiting_.emplace(generation, std::move(kept));
  else
    start(generation, std::move(kept));
}

void FocusCopyWorker::start(std::uint64_t generation, std::vector<std::vector<std::uint64_t>> kept) {
  running_ = BackgroundTask<Done>([this, generation, kept = std::move(kept)] {
#if defined(__linux__)
    // Below the window's thread, as the selections are (selection_worker.cpp).
    setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);
#endif
    Done done;
    done.generation = generation;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      done.copy = std::make_shared<const FocusCopy>(files_, kept);
    } catch (const std::exception& e) {
      done.error = e.what();
    }
    done.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return done;
  });
}

std::optional<FocusCopyWorker::Done> FocusCopyWorker::poll(bool wait) {
  std::optional<Done> newest;
  for (;;) {
    if (!running_.valid()) {
      if (!waiting_) return newest;
      auto [generation, kept] = std::move(*waiting_);
      waiting_.reset();
      start(generation, std::move(kept));
    }
    if (!wait && !running_.ready()) return newest;
    newest = running_.get();
  }
}

}  // namespace vxl::app
