#include "viewer/app/selection_worker.h"

#include <chrono>
#include <exception>

#if defined(__linux__)
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace vxl::app {

SelectionWorker::SelectionWorker(std::vector<const VxlFile*> files, std::shared_ptr<VoxelVoxlinesCache> indexes)
    : files_(std::move(files)), indexes_(std::move(indexes)) {}

// running_'s destructor waits for a selection still running.
SelectionWorker::~SelectionWorker() = default;

void SelectionWorker::request(std::uint64_t revision, SelectionCriteria criteria) {
  if (running_.valid())
    waiting_.emplace(revision, std::move(criteria));
  else
    start(revision, std::move(criteria));
}

void SelectionWorker::start(std::uint64_t revision, SelectionCriteria criteria) {
  running_ = BackgroundTask<Done>([this, revision, criteria = std::move(criteria)] {
#if defined(__linux__)
    // Below the window's thread (and the software rasteriser's, where there is no GPU), so that the frames
    // keep their budget on a machine with few cores; the threads the selection starts inherit it.
    setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);
#endif
    Done done;
    done.revision = revision;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      done.selection = select_in_scene(files_, criteria, indexes_.get());
    } catch (const std::exception& e) {
      done.error = e.what();
    }
    done.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return done;
  });
}

std::optional<SelectionWorker::Done> SelectionWorker::poll(bool wait) {
  std::optional<Done> newest;
  for (;;) {
    if (!running_.valid()) {
      if (!waiting_) return newest;
      auto [revision, criteria] = std::move(*waiting_);
      waiting_.reset();
      start(revision, std::move(criteria));
    }
    if (!wait && !running_.ready()) return newest;
    newest = running_.get();
  }
}

}  // namespace vxl::app
