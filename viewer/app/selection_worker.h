// The window's selections, computed off its thread (newest_request_worker.h): a region dragged across a large
// file asks for a new selection every frame, and one can take longer than a frame (hundreds of milliseconds on
// 10^7 streamlines where a region meets dense voxels), so the frames keep their budget and the picture takes each
// selection when it is ready. The files' per-voxel indexes (VoxelVoxlines) come from the shared cache: the files'
// own, or built by the first run that needs them (or by a renderer sharing the cache) and reused.
#pragma once

#include <memory>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "viewer/app/newest_request_worker.h"
#include "viewer/app/scene_selection.h"

namespace vxl::app {

// A request: the regions as of the number it is given (their revision). The files must outlive the worker; they
// are only read (memory-mapped), so the worker's thread and the window's may read them at once.
class SelectionWorker : public NewestRequestWorker<SelectionCriteria, SceneSelection> {
 public:
  SelectionWorker(std::vector<const VxlFile*> files, std::shared_ptr<VoxelVoxlinesCache> indexes)
      : NewestRequestWorker([files = std::move(files), indexes = std::move(indexes)](const SelectionCriteria& c) {
          return select_in_scene(files, c, indexes.get());
        }) {}
};

}  // namespace vxl::app
