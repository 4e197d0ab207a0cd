// Work the window asks for again and again where only the newest answer matters (a selection while a region is
// dragged, the focus copy of a selection), run off the window's thread: one runs at a time, and a request made
// while it runs replaces any other still waiting. The thread runs below the window's priority (and the software
// rasteriser's, where there is no GPU), so that the frames keep their budget on a machine with few cores; the
// threads the work starts inherit it.
#pragma once

#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#if defined(__linux__)
#include <sys/resource.h>
#include <unistd.h>
#endif

#include "format/base/parallel.h"

namespace vxl::app {

// The worker's nice value: below the window's 0, not so far below that it only runs where the frames leave a core.
// On 2 cores with llvmpipe, a region dragged through 10M streamlines: at 10 a selection got about a tenth of the
// cores while a frame drew; at 5 the selections came a third sooner, the frames keeping their budget; at 0 the frames
// lost it (docs/performance.md, "How far below the window's priority").
inline constexpr int kWorkerNice = 5;

template <typename Request, typename Result>
class NewestRequestWorker {
 public:
  // `run` is called on the worker's thread, one request at a time; what it throws comes back as an error.
  explicit NewestRequestWorker(std::function<Result(const Request&)> run) : run_(std::move(run)) {}
  NewestRequestWorker(const NewestRequestWorker&) = delete;
  NewestRequestWorker& operator=(const NewestRequestWorker&) = delete;

  // The work of `request`, numbered `number` by the caller (e.g. the regions' revision).
  void request(std::uint64_t number, Request request) {
    if (running_.valid())
      waiting_.emplace(number, std::move(request));
    else
      start(number, std::move(request));
  }
  // Forgets the request waiting, if any; one running still finishes.
  void cancel_waiting() { waiting_.reset(); }
  bool busy() const { return running_.valid(); }

  struct Done {
    std::uint64_t number = 0;
    std::optional<Result> result;  // empty when it failed
    std::string error;             // why it failed
    double ms = 0;                 // its run's time
  };
  // The newest work finished since the last call, if any, and the waiting request started. With `wait`, blocks
  // until every request made so far is done (scripted windows and tests).
  std::optional<Done> poll(bool wait = false) {
    std::optional<Done> newest;
    for (;;) {
      if (!running_.valid()) {
        if (!waiting_) return newest;
        auto [number, request] = std::move(*waiting_);
        waiting_.reset();
        start(number, std::move(request));
      }
      if (!wait && !running_.ready()) return newest;
      newest = running_.get();
    }
  }

 private:
  void start(std::uint64_t number, Request request) {
    running_ = BackgroundTask<Done>([this, number, request = std::move(request)] {
#if defined(__linux__)
      setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kWorkerNice);
#endif
      Done done;
      done.number = number;
      const auto t0 = std::chrono::steady_clock::now();
      try {
        done.result = run_(request);
      } catch (const std::exception& e) {
        done.error = e.what();
      }
      done.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      return done;
    });
  }

  std::function<Result(const Request&)> run_;
  std::optional<std::pair<std::uint64_t, Request>> waiting_;
  BackgroundTask<Done> running_;  // last: its destructor waits for the run in progress, which uses run_
};

}  // namespace vxl::app
