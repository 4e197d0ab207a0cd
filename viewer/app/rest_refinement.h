// What the window does with a picture while nothing changes (voxview's refinement at rest). A picture drawn
// whole while the camera moved may be coarse (frame_budget.h): at rest it is redrawn at the scene's level in
// pieces that each fit the frame budget (Renderer::begin_pieces), the coarse picture staying on screen until
// the full one is complete, so that input is taken between pieces. Then, "exact when still": where the
// context has OpenGL 4.3 and the exact mode is the mode's reference (RenderModeInfo::refines_to_exact), the
// picture is drawn once more in the exact mode, run by run. A change of view or settings starts over. Pure
// logic: which stage comes next; the window draws.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "viewer/render/render_settings.h"

namespace vxl::app {

enum class RestStage {
  FullDetail,  // drawing the scene's level in pieces
  Exact,       // drawing the exact mode in pieces
  Done,        // nothing more to draw until something changes
};

class RestRefinement {
 public:
  // exact_available: the context has OpenGL 4.3. exact_when_still: the user's choice (--no-exact-when-still
  // and the E key turn it off).
  RestRefinement(bool exact_available, bool exact_when_still)
      : exact_available_(exact_available), exact_when_still_(exact_when_still) {}

  // A picture was drawn whole in `mode`, at full detail (the scene's level) or coarser: the stages start over.
  void drawn_whole(RenderMode mode, bool full_detail);
  // The current stage's pieces are complete: the next stage.
  void stage_complete();
  RestStage stage() const { return stage_; }
  // The mode the current stage draws in.
  RenderMode stage_mode() const { return stage_ == RestStage::Exact ? RenderMode::Exact : mode_; }

  bool exact_when_still() const { return exact_when_still_; }
  // Turning it on at rest goes on to exact; turning it off drops an exact stage under way (the full-detail
  // picture stays) or, once the exact picture is on screen, draws the mode's own picture again.
  void set_exact_when_still(bool on);

  // What the panel says: "refining to full detail: 40 %" (with a level on the way: "refining to full detail:
  // level 2, 40 %"), "exact when still: 12 %", "exact", "" (full detail).
  std::string describe(double progress, std::optional<std::uint32_t> level_on_the_way = std::nullopt) const;

 private:
  bool wants_exact() const;
  bool exact_available_, exact_when_still_;
  RenderMode mode_ = RenderMode::Axis;
  RestStage stage_ = RestStage::Done;
  bool exact_shown_ = false;  // the picture on screen is the exact stage's (not the exact mode's own)
};

}  // namespace vxl::app
