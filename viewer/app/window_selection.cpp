// The window's selection: the regions edited in the window, selected on a worker (selection_worker.h),
// taken into the picture as focus and context (with focus first's copy, focus_copy_worker.h), waited for at a
// scripted drag's end, and written out on request.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

#include "converter/selection/selection_output.h"
#include "viewer/app/glfw_window.h"
#include "viewer/app/viewer_window.h"

namespace vxl::app {

namespace {

// The most a file's voxlines of one level may take (the shared cache keeps them, PlacedVoxline each): a fine
// level of a large file (level 1 of 10^7 streamlines: 6.5M voxlines, about 160 MB) is selected through the whole
// index.
constexpr std::uint64_t kLevelVoxlinesBytes = std::uint64_t(64) << 20;

}  // namespace

std::uint32_t ViewerWindow::selection_level(bool dragging) const {
  if (!dragging || moving_level_ == 0) return 0;
  for (const VxlFile* f : files_) {
    if (f->level_count() <= moving_level_) return 0;
    const std::uint64_t voxlines = f->meta().voxline_count >> (3 * moving_level_);  // about 1/8 a level
    if (voxlines * sizeof(PlacedVoxline) > kLevelVoxlinesBytes) return 0;
  }
  return moving_level_;
}

void ViewerWindow::update_selection(bool wait, bool dragging) {
  // The panel's list, every frame: which region is active changes without a new selection.
  stats_.regions.clear();
  for (std::size_t i = 0; i < regions_.regions().size(); ++i) {
    const EditorRegion& r = regions_.regions()[i];
    stats_.regions.push_back(
        {r.role_name(), r.argument(), r.streamlines, r.centre.has_value(), regions_.active() == i, r.radius});
  }
  const std::uint32_t level = selection_level(dragging);
  if (selection_revision_ != regions_.revision() || level != selection_level_asked_) {
    selection_revision_ = regions_.revision();
    selection_level_asked_ = level;
    if (regions_.empty()) {
      cleared_revision_ = regions_.revision();
      if (selection_) apply_selection(std::nullopt);
    } else {
      try {
        if (drawn_) read_ahead_selection_tables_once();  // at opening, once the first level is read (the constructor)
        SelectionCriteria criteria = regions_.criteria();
        if (level > 0) criteria.level = level;
        selection_worker_.request(regions_.revision(), std::move(criteria));
        if (!selection_) stats_.selection = "selecting the regions' streamlines ...";
      } catch (const std::exception& e) {  // a region that does not parse: said, and no selection
        set_error(e.what());
        if (selection_) apply_selection(std::nullopt);
      }
    }
  }
  std::optional<SelectionWorker::Done> done = selection_worker_.poll(wait);
  if (!done || (cleared_revision_ && done->number <= *cleared_revision_)) return;
  if (!done->error.empty()) {
    set_error(done->error);
    apply_selection(std::nullopt);
    return;
  }
  selection_ms_.push_back(done->ms);
  selection_levels_.push_back(done->result->level);
  // Counts only for the regions they were computed with (the list may have changed since), and of every streamline.
  const std::uint32_t searched = done->result->level;
  if (done->number == regions_.revision() && searched == 0) regions_.set_counts(done->result->streamlines_per_region);
  stats_.selection = std::to_string(done->result->selected) +
                     (searched > 0 ? " streamlines of level " + std::to_string(searched) + " selected while moving ("
                                   : " of " + std::to_string(done->result->total) + " streamlines selected (") +
                     std::to_string(int(done->ms + 0.5)) + " ms)";
  RenderSettings& s = state_.settings;
  // Regions added in the window to a scene started without: the context faint, as --context-opacity's default.
  if (s.find_style(SceneGroups::kContext) == nullptr)
    s.style_of(SceneGroups::kContext).opacity = std::min(1.0f, 0.02f / s.opacity);
  apply_selection(std::move(done->result));
}

void ViewerWindow::read_ahead_selection_tables_once() {
  if (selection_tables_asked_) return;
  for (const VxlFile* f : files_) read_ahead_selection_tables(*f);
  selection_tables_asked_ = true;
}

void ViewerWindow::apply_selection(std::optional<SceneSelection> selection) {
  selection_ = std::move(selection);
  if (!selection_) stats_.selection.clear();
  ++selection_generation_;
  session_->set_groups(selection_ ? std::optional<SceneGroups>(selection_->groups) : std::nullopt);
  // Focus first: the old copy held the old selection; the new one's comes from the worker.
  if (session_->has_focus()) session_->set_focus({}, nullptr);
  focus_copies_.cancel_waiting();
  // Not while a newer selection runs (a drag): its copy would be stale before it is done; nor of one level's
  // selection, which holds no more than the moving frames draw.
  if (selection_ && focus_first_wanted_ && selection_->selected > 0 && selection_->level == 0 &&
      !selection_worker_.busy())
    focus_copies_.request(selection_generation_, selection_->kept);
  const SceneGroups groups = selection_ ? selection_->groups : SceneGroups(files_);
  stats_.groups.clear();
  for (const SceneGroup& g : groups.groups()) stats_.groups.emplace_back(g.name, g.streamlines);
  for (std::size_t i = 0; i < stats_.regions.size(); ++i)
    stats_.regions[i].streamlines = regions_.regions()[i].streamlines;
}

void ViewerWindow::update_focus_copy(bool wait) {
  std::optional<FocusCopyWorker::Done> done = focus_copies_.poll(wait);
  if (!done || !selection_ || done->number != selection_generation_) return;  // a selection since
  if (!done->result) {
    set_error("the focus is drawn with the context: " + done->error);
    return;
  }
  session_->set_focus(selection_->kept, *done->result);
  ++selection_generation_;  // the picture changes: drawn again, the focus at full detail
}

bool ViewerWindow::drag_end_settled() {
  if (drag_end_) return true;
  const auto now = std::chrono::steady_clock::now();
  if (!drag_end_since_) drag_end_since_ = now;
  // busy(): asked for and not yet taken into the picture (a finished one is taken by the next poll). The copy
  // only matters when the last picture, drawn at the scene's level, is coarser than full detail.
  const bool pending = selection_revision_ != regions_.revision() || selection_worker_.busy() ||
                       level_selection_shown() || (detail_.level > 0 && focus_copies_.busy());
  const bool timed_out = pending && now - *drag_end_since_ >= kDragEndWaitLimit;
  if (pending && !timed_out) return false;
  drag_end_ = DragEndWait{now != *drag_end_since_,
                          std::chrono::duration<double, std::milli>(now - *drag_end_since_).count(), timed_out};
  if (timed_out)
    set_error("the drag's last selection or focus copy was not ready after " +
              std::to_string(kDragEndWaitLimit.count()) + " s: the last picture may not show it");
  return true;
}

void ViewerWindow::save_selection() {
  if (!selection_) {
    set_error("no selection to save: add a region first (G)");
    return;
  }
  for (std::size_t i = 0; i < files_.size(); ++i) {
    const std::string path =
        stamped_name("voxview-selection-", files_.size() > 1 ? "-" + std::to_string(i) + ".tck" : ".tck").string();
    try {
      write_selection(*files_[i], StreamlineSubset(files_[i]->meta().streamline_count, selection_->kept[i]), path, {},
                      {});
      stats_.status = "selection saved to " + path;
      std::printf("voxview: %zu streamlines saved to %s\n", selection_->kept[i].size(), path.c_str());
      std::fflush(stdout);
    } catch (const std::exception& e) {
      set_error(e.what());
    }
  }
}

}  // namespace vxl::app
