// The level of detail one view is drawn at: the finest whose visible part fits the GPU memory budget
// (a slab or a close view of a large scene is drawn finer than the whole scene could be). Computed on the
// scene's layouts, without GL, so that neither the window nor headless rendering makes a renderer only to
// measure a view.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
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
  // The coarsest level every file has.
  std::uint32_t coarsest() const { return SceneLayout::coarsest_level(files_); }

 private:
  std::vector<const VxlFile*> files_;
  std::uint64_t span_texels_;
  std::map<std::uint32_t, std::unique_ptr<SceneLayout>> layouts_;
};

// The finest level, from full detail up to the scene's (detail.level), whose spans visible from `camera`
// with `clipping` fit detail.budget; the scene's level when none finer fits or when --level forced it.
std::uint32_t level_for_view(LevelLayouts& layouts, const SceneDetail& detail, const Camera& camera, double aspect,
                             const SceneBounds& bounds, const Clipping& clipping);

// Focus first (README "Virtual dissection"): when the budget forces the scene coarser than full detail, a
// selection's focus is drawn from its full-detail copy (focus_copy.h) and the context coarser. The copy's
// bytes count against the budget first; the context takes the finest level whose bytes fit what is left
// (coarser than the scene's level when the focus needs the room). `bytes` measures a layout: its visible
// spans for one view (view_bytes), its whole copy for a turntable (upload_bytes).
struct FocusFirstLevels {
  std::uint32_t context = 0;      // the context's level; the focus is drawn at level 0
  std::uint64_t focus_bytes = 0;  // what the focus's copy takes of the budget
};
using LayoutBytes = std::function<std::uint64_t(const SceneLayout&)>;
// nullopt when --level forced the level, or when the copy with the context even at the files' coarsest level
// does not fit: then the focus is drawn with the context, at one level, as without a focus.
std::optional<FocusFirstLevels> focus_first_levels(LevelLayouts& context, const SceneLayout& focus,
                                                   const SceneDetail& detail, const LayoutBytes& bytes);
// `bytes` for one view: the spans visible from `camera` with `clipping`.
LayoutBytes visible_bytes(const Camera& camera, double aspect, const SceneBounds& bounds, const Clipping& clipping);

}  // namespace vxl::app
