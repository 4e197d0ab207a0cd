// One scene as voxview shows it, shared by the window and headless rendering: the files, the anatomical
// image, the level of detail and GPU memory budget, the scene's layout per level (views measured without
// GL, view_level.h) and the renderers per level, which share one GPU memory pool and the selection's groups.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "format/vxl_file.h"
#include "viewer/app/focus_copy.h"
#include "viewer/app/scene_detail.h"
#include "viewer/app/view_level.h"
#include "viewer/app/viewer_options.h"
#include "viewer/render/gpu_memory_pool.h"
#include "viewer/render/renderer.h"
#include "viewer/render/scene_groups.h"
#include "viewer/render/volume.h"

namespace vxl::app {

struct PictureLevels {
  std::uint32_t level = 0;                      // the level of the whole picture drawn at one level
  std::optional<FocusFirstLevels> focus_first;  // set: the focus at full detail, the context at its level
  // The level the picture's context is drawn at.
  std::uint32_t context_level() const { return focus_first ? focus_first->context : level; }
};

class ViewerSession {
 public:
  // Opens the inputs (converting a source tractogram) and reads --image: a bad file or image fails here,
  // before any GL work.
  explicit ViewerSession(const ViewerOptions& options);
  ViewerSession(const ViewerSession&) = delete;
  ViewerSession& operator=(const ViewerSession&) = delete;

  // Chooses the level of detail, the span size and the GPU memory budget (scene_detail.h) for the options'
  // --level, --gpu-memory and --span-texels. Needs a current GL context (the driver's limits); before any
  // layout, view or renderer.
  // `one_renderer`: only one renderer will draw (headless), so a level that fits the budget whole takes spans as
  // large as the driver allows (fewer draws), where the window's renderers share the budget and page in small spans
  // (drawn one span a draw where runs are long, line_pass.h, they draw as fast).
  void choose_detail(const ViewerOptions& options, bool one_renderer = false);
  const SceneDetail& detail() const { return *detail_; }
  // The levels the files hold (their coarsest level + 1), for messages.
  std::uint32_t levels_in_files() const;

  const std::vector<VxlFile>& opened() const { return opened_; }
  const std::vector<const VxlFile*>& files() const { return files_; }
  const Volume* image() const { return image_ ? &*image_ : nullptr; }
  // Frees the image once every renderer that will draw it is made (headless draws with one).
  void release_image() { image_.reset(); }

  // The scene's layout at `level` (no GL), e.g. for the default framing.
  const SceneLayout& layout_at(std::uint32_t level) { return layouts_->at(level); }
  // What the renderers' projection covers: the lines' bounds joined with the image's box.
  const SceneBounds& bounds() const { return bounds_; }
  // The layout the default framing is measured on: full detail where one view (`one_view`: not a turntable) may be
  // drawn finer than the scene's level, else the scene's level.
  const SceneLayout& framing_layout(bool one_view);
  // The levels one picture is drawn at, the one policy of the window and headless rendering (view_level.h). For
  // one view (`camera`): the finest level whose visible part with `clipping` fits the budget; for the whole scene
  // (null: a turntable's frames) the scene's level. With a focus set and that level coarser than full detail,
  // focus first where the copy fits beside the context; where it does not, the focus is dropped (set_focus with
  // none) and the scene drawn at one level, as without it.
  PictureLevels picture_levels(const Camera* camera, double aspect, const Clipping& clipping);
  // Whether a selection's full-detail copy (set_focus) is worth making for pictures drawn at `coarsest_drawn` at
  // most: focus first only draws pictures coarser than full detail, and never where --level fixed the level.
  bool focus_copy_needed(std::uint32_t coarsest_drawn) const { return !detail_->forced && coarsest_drawn > 0; }

  // The span size of a renderer at `level`: whole_span_texels for one renderer at the scene's level or coarser
  // (it fits the budget whole), else span_texels.
  std::uint64_t span_texels_at(std::uint32_t level) const;
  // The renderer of `level`, made on first use with the image and the current groups; `eager`: it uploads
  // its whole level at once when made (else span by span as frames need them).
  Renderer& renderer_at(std::uint32_t level, bool eager);
  // Every renderer's groups, now and when made later: a selection's focus and context, or (none) the files'
  // own groups again.
  void set_groups(const std::optional<SceneGroups>& groups);
  // Focus first (view_level.h): the selection's full-detail copy (focus_copy.h; kept: per file, its selected
  // streamlines), made here without GL, replacing an earlier one and its renderers; none when nothing is
  // selected. Throws vxl::Error when the copy cannot be written.
  void set_focus(const std::vector<std::vector<std::uint64_t>>& kept);
  // The same with a copy of `kept` made elsewhere (the window's, off its thread); null: no focus copy.
  void set_focus(const std::vector<std::vector<std::uint64_t>>& kept, std::shared_ptr<const FocusCopy> copy);
  bool has_focus() const { return focus_layout_.has_value(); }
  // The segments of the focus's full-detail copy (0 without one).
  std::uint64_t focus_segments() const;
  // The renderer of the context's files at `context_level` and the focus's copy at full detail, one scene
  // (its groups: SceneGroups::focus_first), made on first use like renderer_at. Needs set_focus.
  Renderer& focus_first_renderer(std::uint32_t context_level, bool eager);
  // Every renderer's checks of what it uploaded (Renderer::check_uploaded): rethrows a failure; with `wait`,
  // once all have run.
  void check_uploaded(bool wait);
  // What the renderers have uploaded to the GPU so far (their memory pool's tally; empty before choose_detail).
  UploadTally uploads() const { return gpu_memory_ ? gpu_memory_->uploads() : UploadTally{}; }
  // The files' per-voxel indexes, shared by the renderers and the selections (built once, on first use).
  const std::shared_ptr<VoxelVoxlinesCache>& indexes() const { return indexes_; }

 private:
  std::vector<VxlFile> opened_;
  std::vector<const VxlFile*> files_;
  std::optional<Volume> image_;
  SceneBounds bounds_;  // the lines joined with the image's box: what the renderer's projection covers
  std::shared_ptr<VoxelVoxlinesCache> indexes_;
  std::optional<SceneDetail> detail_;
  bool one_renderer_ = false;                  // choose_detail's
  std::shared_ptr<GpuMemoryPool> gpu_memory_;  // every level's renderer shares it: together they never take more
  std::optional<LevelLayouts> layouts_;
  std::map<std::uint32_t, std::unique_ptr<Renderer>> renderers_;
  std::optional<SceneGroups> groups_;  // the selection's, when there is one
  // Focus first: the copy (outliving its renderers), its layout at full detail, its selection.
  std::shared_ptr<const FocusCopy> focus_;
  std::optional<SceneLayout> focus_layout_;
  std::vector<std::vector<std::uint64_t>> focus_kept_;
  std::map<std::uint32_t, std::unique_ptr<Renderer>> focus_renderers_;
};

}  // namespace vxl::app
