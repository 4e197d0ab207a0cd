// The window's selections, computed off its thread (newest_request_worker.h): a region dragged across a large
// file asks for a new selection every frame, and one can take longer than a frame (hundreds of milliseconds on
// 10^7 streamlines where a region meets dense voxels), so the frames keep their budget and the picture takes each
// selection when it is ready. The files' per-voxel indexes (VoxelVoxlines) come from the shared cache: the files'
// own, or built by the first run that needs them (or by a renderer sharing the cache) and reused; each file's
// VoxlineBoxes, the worker's own, carry what one selection learned of its voxels to the next.
#pragma once

#include <memory>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "converter/selection/voxline_boxes.h"
#include "viewer/app/newest_request_worker.h"
#include "viewer/app/scene_selection.h"

namespace vxl::app {

// A request: the regions as of the number it is given (their revision). The files must outlive the worker; they
// are only read (memory-mapped), so the worker's thread and the window's may read them at once. A request with a
// level (criteria.level, which every file has) searches that level's streamlines alone, through each file's voxlines
// of it in the shared cache (made once, by the worker or a renderer drawing that level): a picture drawn at that level
// or a coarser one needs no more, and on 10^7 streamlines the coarsest level's search takes about a millisecond.
class SelectionWorker : public NewestRequestWorker<SelectionCriteria, SceneSelection> {
 public:
  SelectionWorker(std::vector<const VxlFile*> files, std::shared_ptr<VoxelVoxlinesCache> indexes)
      : NewestRequestWorker([files, indexes = std::move(indexes), boxes = boxes_of(files)](const SelectionCriteria& c) {
          return select_in_scene(files, c, indexes.get(), *boxes);
        }) {}

 private:
  using Boxes = std::vector<std::unique_ptr<VoxlineBoxes>>;
  static std::shared_ptr<Boxes> boxes_of(const std::vector<const VxlFile*>& files) {
    auto boxes = std::make_shared<Boxes>();
    for (const VxlFile* f : files) boxes->push_back(std::make_unique<VoxlineBoxes>(*f));
    return boxes;
  }
};

}  // namespace vxl::app
