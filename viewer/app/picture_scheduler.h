// What the window draws each frame, and at which level of detail: a changed picture is drawn whole — the
// first at a coarse level (so that it comes at once), while the camera moves or a setting changes at the
// finest level the frame budget allows (frame_budget.h), a script's last frame at the scene's level — and an
// unchanged one is refined at rest a piece a frame (rest_refinement.h): to the finest level whose visible
// part fits the GPU memory budget (view_level.h) — through each level between, each shown once complete, so that
// a picture eight times denser comes after about an eighth of the time — then to the exact picture; first, where the
// whole picture left a selection's full-detail focus copy out, to that picture with the copy. Pure logic, testable
// without GL: the window draws what it says and reports back.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "viewer/app/frame_budget.h"
#include "viewer/app/frame_log.h"
#include "viewer/app/rest_refinement.h"

namespace vxl::app {

enum class PictureWork {
  None,   // the picture on screen stays
  Whole,  // draw the picture whole at the task's level
  Piece,  // draw the refinement's next piece at the task's level, in rest().stage_mode()
};

struct PictureTask {
  PictureWork work = PictureWork::None;
  std::uint32_t level = 0;
  FrameWork frame_work = FrameWork::Whole;  // for --stats
  // The picture on screen already was the view's full detail: the refinement skipped that stage (what the
  // panel says of it changed).
  bool stage_skipped = false;
};

class PictureScheduler {
 public:
  // scene_level, level_forced: the scene's level of detail and whether --level chose it (scene_detail.h);
  // first_level: the first picture's (first_picture_level).
  PictureScheduler(FrameBudget budget, RestRefinement rest, std::uint32_t scene_level, bool level_forced,
                   std::uint32_t first_level);

  // This frame's work. changed: the picture on screen no longer shows the view and settings (or there is
  // none yet); scripted_last: a script's last frame, drawn whole at the scene's level; closing: the window
  // closes after this frame (nothing is refined then). level_for_view: the finest level whose visible part
  // fits the GPU memory budget, asked once per picture drawn whole, when its refinement starts.
  PictureTask next(bool changed, bool scripted_last, bool closing,
                   const std::function<std::uint32_t()>& level_for_view);

  // A picture was drawn whole in `mode` at `level`, in `ms`: the refinement starts over. focus_left_out: it drew the
  // focus from the context's level, its full-detail copy not fitting the frame budget: the refinement first draws
  // that picture again with the copy, in pieces at the same level (focus_stage()), then goes on.
  void drawn_whole(RenderMode mode, std::uint32_t level, double ms, bool focus_left_out = false);
  // A piece of the refinement was drawn; `completes`: its stage's picture is complete and on screen.
  void piece_drawn(bool completes);

  // Whether the current stage's pieces have begun (Renderer::begin_pieces); a whole picture, a failed piece
  // or a change of "exact when still" abandons them.
  bool pieces_begun() const { return pieces_begun_; }
  void begin_pieces() { pieces_begun_ = true; }
  void abandon_pieces() { pieces_begun_ = false; }
  // What the next frames draw besides the context and share the cores with: whole pictures are measured and
  // their level chosen under it (frame_budget.h).
  void set_load(FrameLoad load) { load_ = load; }
  // The user turned "exact when still" on or off (the panel, key E).
  void set_exact_when_still(bool on);

  // The refinement's pieces draw the whole picture's level again with the focus copy (drawn_whole's focus_left_out).
  bool focus_stage() const { return focus_left_out_; }
  const RestRefinement& rest() const { return rest_; }
  RestRefinement& rest() { return rest_; }
  // The level of the picture on screen.
  std::uint32_t drawn_level() const { return drawn_level_; }
  // The level the refinement to full detail is drawing on the way to the view's level; none when it draws that
  // level itself (or another stage).
  std::optional<std::uint32_t> level_on_the_way() const;

 private:
  std::uint32_t whole_level(bool scripted_last) const;
  // The level the full-detail stage draws next: one finer than the picture on screen, until the view's level.
  std::uint32_t full_detail_step() const;

  FrameBudget budget_;
  FrameLoad load_;
  RestRefinement rest_;
  std::uint32_t scene_level_;
  bool level_forced_;
  std::uint32_t first_level_;
  bool drawn_any_ = false;         // a picture has been drawn whole
  std::uint32_t drawn_level_ = 0;  // the level of the picture on screen
  // The level the refinement draws this view at; none until the refinement has chosen it.
  std::optional<std::uint32_t> rest_level_;
  bool pieces_begun_ = false;
  bool focus_left_out_ = false;
};

}  // namespace vxl::app
