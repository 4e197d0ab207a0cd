// The window's focus copies (focus_copy.h), written off its thread (newest_request_worker.h): a copy converts
// every selected streamline again (about 0.3 s for 1,600 streamlines on two cores), longer than a frame, so the
// picture shows a new selection at once, at one level, and draws its focus at full detail when the copy is ready.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "viewer/app/focus_copy.h"
#include "viewer/app/newest_request_worker.h"

namespace vxl::app {

// A request: per file, its selected streamlines, numbered by the selection's generation. The files must outlive
// the worker (only read, memory-mapped).
class FocusCopyWorker
    : public NewestRequestWorker<std::vector<std::vector<std::uint64_t>>, std::shared_ptr<const FocusCopy>> {
 public:
  explicit FocusCopyWorker(std::vector<const VxlFile*> files)
      : NewestRequestWorker([files = std::move(files)](const std::vector<std::vector<std::uint64_t>>& kept) {
          return std::make_shared<const FocusCopy>(files, kept);
        }) {}
};

}  // namespace vxl::app
