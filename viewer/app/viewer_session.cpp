#include "viewer/app/viewer_session.h"

#include "format/vxl_fetch_plan.h"
#include "viewer/anatomy/nifti_volume.h"
#include "viewer/app/scene_source.h"
#include "viewer/render/scene_layout.h"

namespace vxl::app {

ViewerSession::ViewerSession(const ViewerOptions& o)
    : opened_(open_scenes(o.inputs, scene_source_options(o))),
      files_(pointers(opened_)),
      indexes_(std::make_shared<VoxelVoxlinesCache>(files_)) {
  if (o.image) image_ = read_nifti_volume(*o.image);
  bounds_ = scene_bounds(files_, image());
}

void ViewerSession::choose_detail(const ViewerOptions& o, bool one_renderer) {
  detail_ = choose_scene_detail(files_, o.level, o.gpu_memory, o.span_texels);
  one_renderer_ = one_renderer;
  gpu_memory_ = std::make_shared<GpuMemoryPool>(detail_->budget);
  layouts_.emplace(files_, detail_->span_texels);
}

std::uint32_t ViewerSession::levels_in_files() const { return SceneLayout::coarsest_level(files_) + 1; }

const SceneLayout& ViewerSession::framing_layout(bool one_view) {
  return layouts_->at(one_view && !detail_->forced ? 0 : detail_->level);
}

PictureLevels ViewerSession::picture_levels(const Camera* camera, double aspect, const Clipping& clipping) {
  const bool one_view = camera != nullptr && !detail_->forced && detail_->level > 0;
  PictureLevels p;
  p.level = one_view ? level_for_view(*layouts_, *detail_, *camera, aspect, bounds_, clipping) : detail_->level;
  if (!has_focus() || !focus_copy_needed(p.level)) return p;
  p.focus_first =
      focus_first_levels(*layouts_, *focus_layout_, *detail_,
                         one_view ? visible_bytes(*camera, aspect, bounds_, clipping)
                                  : LayoutBytes([](const SceneLayout& layout) { return layout.upload_bytes(); }));
  if (!p.focus_first) set_focus({}, nullptr);
  return p;
}

std::uint64_t ViewerSession::span_texels_at(std::uint32_t level) const {
  return one_renderer_ && level >= detail_->level ? detail_->whole_span_texels : detail_->span_texels;
}

Renderer& ViewerSession::renderer_at(std::uint32_t level, bool eager) {
  std::unique_ptr<Renderer>& r = renderers_[level];
  if (!r) {
    // Its level's bytes asked of the disk at once, where the file is not in the page cache: an eager renderer uploads
    // them now, another as frames need them (the reads then come in the background, not one fault at a time).
    for (const VxlFile* f : files_) read_ahead_level(*f, level);
    r = std::make_unique<Renderer>(files_, span_texels_at(level), level, gpu_memory_, eager);
    r->share_indexes(indexes_);
    if (image_) r->set_volume(*image_);
    if (groups_) r->set_groups(*groups_);
  }
  return *r;
}

void ViewerSession::check_uploaded(bool wait) {
  for (auto* renderers : {&renderers_, &focus_renderers_})
    for (auto& [level, renderer] : *renderers) renderer->check_uploaded(wait);
}

void ViewerSession::set_focus(const std::vector<std::vector<std::uint64_t>>& kept) {
  bool any = false;
  for (const auto& k : kept) any |= !k.empty();
  set_focus(kept, any ? std::make_shared<const FocusCopy>(files_, kept) : nullptr);
}

void ViewerSession::set_focus(const std::vector<std::vector<std::uint64_t>>& kept,
                              std::shared_ptr<const FocusCopy> copy) {
  focus_renderers_.clear();  // before the copy they draw
  focus_layout_.reset();
  focus_ = std::move(copy);
  focus_kept_ = kept;
  if (focus_ && !focus_->files().empty()) focus_layout_.emplace(focus_->files(), detail_->span_texels, 0);
}

std::uint64_t ViewerSession::focus_segments() const {
  std::uint64_t segments = 0;
  if (focus_)
    for (const VxlFile* f : focus_->files()) segments += f->meta().segment_count;
  return segments;
}

Renderer& ViewerSession::focus_first_renderer(std::uint32_t context_level, bool eager) {
  std::unique_ptr<Renderer>& r = focus_renderers_[context_level];
  if (!r) {
    std::vector<const VxlFile*> all = files_;
    all.insert(all.end(), focus_->files().begin(), focus_->files().end());
    std::vector<std::uint32_t> levels(files_.size(), context_level);
    levels.resize(all.size(), 0);  // the focus's copies at full detail
    // The largest spans only where the context and the copy fit the budget whole in them: the choice of the context's
    // level counted their visible part, which in spans that large is nearly all of them.
    std::uint64_t span_texels = span_texels_at(context_level);
    if (span_texels != detail_->span_texels && SceneLayout(all, span_texels, levels).upload_bytes() > detail_->budget)
      span_texels = detail_->span_texels;
    // Its own per-voxel indexes: the session's cover the context's files only.
    r = std::make_unique<Renderer>(all, span_texels, context_level, gpu_memory_, eager, levels);
    if (image_) r->set_volume(*image_);
    r->set_groups(SceneGroups::focus_first(all, files_.size(), focus_kept_));
  }
  return *r;
}

void ViewerSession::set_groups(const std::optional<SceneGroups>& groups) {
  groups_ = groups;
  const SceneGroups drawn = groups ? *groups : SceneGroups(files_);
  for (auto& [level, r] : renderers_) r->set_groups(drawn);
}

}  // namespace vxl::app
