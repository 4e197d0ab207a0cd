// The level of detail one view is drawn at: the finest whose visible part fits the GPU memory budget
// (a slab or a close view of a large scene is drawn finer than the whole scene could be). Computed on the
// scene's layouts, without GL, so that neither the window nor headless rendering makes a renderer only to
// measure a view.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <vector>

#include "viewer/app/scene_detail.h"
#include "viewer/render/camera.h"
#include "viewer/render/clip_planes.h"
#include "viewer/render/scene_layout.h"
#include "viewer/render/view_queries.h"
#include "viewer/render/volume.h"

namespace vxl::app {

// The scene's layout at each level of detail, for one span size, made on first use.
class LevelLayouts {
 public:
  LevelLayouts(std::vector<const VxlFile*> files, std::uint64_t span_texels)
      : files_(std::move(files)), span_texels_(span_texels) {}
  const SceneLayout& at(std::uint32_t level);

 private:
  std::vector<const VxlFile*> files_;
  std::uint64_t span_texels_;
  std::map<std::uint32_t, std::unique_ptr<SceneLayout>> layouts_;
};

// The finest level, from full detail up to the scene's (detail.level), whose spans visible from `camera`
// with `clipping` fit detail.budget; the scene's level when none finer fits or when --level forced it.
std::uint32_t level_for_view(LevelLayouts& layouts, const SceneDetail& detail, const Camera& camera, double aspect,
                             const SceneBounds& bounds, const Clipping& clipping);

}  // namespace vxl::app
