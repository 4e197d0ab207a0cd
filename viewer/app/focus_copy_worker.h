// The window's focus copies (focus_copy.h), written off its thread: a copy converts every selected streamline
// again (about 0.3 s for 1,600 streamlines on two cores), longer than a frame, so the picture shows a new
// selection at once, at one level, and draws its focus at full detail when the copy is ready. The newest
// request wins, as for the selections (selection_worker.h): one runs at a time, and a request made while it
// runs replaces any other still waiting.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "format/base/parallel.h"
#include "viewer/app/focus_copy.h"

namespace vxl::app {

class FocusCopyWorker {
 public:
  // The files must outlive the worker (only read, memory-mapped).
  explicit FocusCopyWorker(std::vector<const VxlFile*> files) : files_(std::move(files)) {}
  FocusCopyWorker(const FocusCopyWorker&) = delete;
  FocusCopyWorker& operator=(const FocusCopyWorker&) = delete;

  // The copy of `kept` (per file, its selected streamlines) for the selection numbered `generation`.
  void request(std::uint64_t generation, std::vector<std::vector<std::uint64_t>> kept);
  // Forgets the request waiting, if any (the selection is gone); one running still finishes.
  void cancel_waiting() { waiting_.reset(); }

  struct Done {
    std::uint64_t generation = 0;
    std::shared_ptr<const FocusCopy> copy;  // null when it failed
    std::string error;
    double ms = 0;
  };
  // The newest copy finished since the last call, if any, and the waiting request started. With `wait`,
  // blocks until every request made so far is done (scripted windows and tests).
  std::optional<Done> poll(bool wait = false);

 private:
  void start(std::uint64_t generation, std::vector<std::vector<std::uint64_t>> kept);

  std::vector<const VxlFile*> files_;
  BackgroundTask<Done> running_;
  std::optional<std::pair<std::uint64_t, std::vector<std::vector<std::uint64_t>>>> waiting_;
};

}  // namespace vxl::app
