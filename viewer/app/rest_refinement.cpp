#include "viewer/app/rest_refinement.h"

#include <cmath>

namespace vxl::app {

bool RestRefinement::wants_exact() const {
  return exact_available_ && exact_when_still_ && render_mode_info(mode_).refines_to_exact;
}

void RestRefinement::drawn_whole(RenderMode mode, bool full_detail) {
  mode_ = mode;
  exact_shown_ = false;
  stage_ = !full_detail ? RestStage::FullDetail : wants_exact() ? RestStage::Exact : RestStage::Done;
}

void RestRefinement::stage_complete() {
  if (stage_ == RestStage::FullDetail) {
    exact_shown_ = false;
    stage_ = wants_exact() ? RestStage::Exact : RestStage::Done;
  } else if (stage_ == RestStage::Exact) {
    exact_shown_ = true;
    stage_ = RestStage::Done;
  }
}

void RestRefinement::set_exact_when_still(bool on) {
  exact_when_still_ = on;
  // A mode without an exact stage (exact itself among them) has nothing to add or take back.
  if (!render_mode_info(mode_).refines_to_exact) return;
  if (!on && exact_shown_) stage_ = RestStage::FullDetail;  // the exact picture is replaced by the mode's own
  if (!on && stage_ == RestStage::Exact) stage_ = RestStage::Done;
  if (on && stage_ == RestStage::Done && wants_exact()) stage_ = RestStage::Exact;
}

std::string RestRefinement::describe(double progress, std::optional<std::uint32_t> level_on_the_way) const {
  const std::string percent = std::to_string(static_cast<int>(std::floor(100 * progress))) + " %";
  switch (stage_) {
    case RestStage::FullDetail:
      return "refining to full detail: " +
             (level_on_the_way ? "level " + std::to_string(*level_on_the_way) + ", " : std::string()) + percent;
    case RestStage::Exact: return "exact when still: " + percent;
    case RestStage::Done: return exact_shown_ ? "exact (the camera is still)" : "";
  }
  return "";
}

}  // namespace vxl::app
