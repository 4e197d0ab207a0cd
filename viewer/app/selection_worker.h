// The window's selections, computed off its thread: a region dragged across a large file asks for a new
// selection every frame, and one can take longer than a frame (hundreds of milliseconds on 10^7
// streamlines where a region meets dense voxels), so the frames keep their budget and the picture takes
// each selection when it is ready. The newest request wins: one runs at a time, and a request made while
// it runs replaces any other still waiting. The files' per-voxel indexes (VoxelVoxlines) are built by the
// first run that needs them, or by a renderer sharing the cache, and reused.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "format/base/parallel.h"
#include "viewer/app/scene_selection.h"

namespace vxl::app {

class SelectionWorker {
 public:
  // The files must outlive the worker; they are only read (memory-mapped), so the worker's thread and the
  // window's may read them at once.
  explicit SelectionWorker(std::vector<const VxlFile*> files, std::shared_ptr<VoxelVoxlinesCache> indexes);
  SelectionWorker(const SelectionWorker&) = delete;
  SelectionWorker& operator=(const SelectionWorker&) = delete;
  ~SelectionWorker();  // waits for the run in progress

  // The selection of `criteria`, the regions as of `revision`.
  void request(std::uint64_t revision, SelectionCriteria criteria);

  struct Done {
    std::uint64_t revision = 0;
    std::optional<SceneSelection> selection;  // empty when it failed
    std::string error;                        // why it failed
    double ms = 0;                            // its run's time (the first run's includes the indexes)
  };
  // The newest selection finished since the last call, if any, and the waiting request started. With
  // `wait`, blocks until every request made so far is done (for scripted windows and tests).
  std::optional<Done> poll(bool wait = false);
  bool busy() const { return running_.valid(); }

 private:
  void start(std::uint64_t revision, SelectionCriteria criteria);

  std::vector<const VxlFile*> files_;
  std::shared_ptr<VoxelVoxlinesCache> indexes_;
  BackgroundTask<Done> running_;
  std::optional<std::pair<std::uint64_t, SelectionCriteria>> waiting_;
};

}  // namespace vxl::app
