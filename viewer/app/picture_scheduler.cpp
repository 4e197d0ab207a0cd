#include "viewer/app/picture_scheduler.h"

namespace vxl::app {

PictureScheduler::PictureScheduler(FrameBudget budget, RestRefinement rest, std::uint32_t scene_level,
                                   bool level_forced, std::uint32_t first_level)
    : budget_(budget), rest_(rest), scene_level_(scene_level), level_forced_(level_forced), first_level_(first_level) {}

std::uint32_t PictureScheduler::whole_level(bool scripted_last) const {
  if (scripted_last) return scene_level_;
  if (!drawn_any_) return first_level_;
  return budget_.level_for(true, load_);
}

PictureTask PictureScheduler::next(bool changed, bool scripted_last, bool closing,
                                   const std::function<std::uint32_t()>& level_for_view) {
  PictureTask task;
  if (changed || scripted_last) {
    task.work = PictureWork::Whole;
    task.level = whole_level(scripted_last);
    return task;
  }
  if (closing || rest_.stage() == RestStage::Done) return task;
  if (focus_left_out_) {
    task.work = PictureWork::Piece;
    task.level = drawn_level_;
    task.frame_work = FrameWork::FocusPiece;
    return task;
  }
  if (!rest_level_) {  // once per picture drawn whole
    rest_level_ = level_for_view();
    if (rest_.stage() == RestStage::FullDetail && *rest_level_ == drawn_level_) {
      rest_.stage_complete();  // the picture on screen is already this view's full detail
      task.stage_skipped = true;
    }
  }
  if (rest_.stage() == RestStage::Done) return task;
  task.work = PictureWork::Piece;
  task.level = rest_.stage() == RestStage::FullDetail ? full_detail_step() : *rest_level_;
  task.frame_work = rest_.stage() == RestStage::Exact ? FrameWork::ExactPiece : FrameWork::FullDetailPiece;
  return task;
}

void PictureScheduler::drawn_whole(RenderMode mode, std::uint32_t level, double ms, bool focus_left_out) {
  focus_left_out_ = focus_left_out;
  if (drawn_any_)
    budget_.record(level, ms, load_);
  else
    budget_.record_first_picture(level, ms);
  // Full detail for any view only at level 0 (or the level --level forces); otherwise the refinement
  // decides, once at rest, which level this view can have.
  rest_.drawn_whole(mode, level == 0 || (level_forced_ && level == scene_level_));
  drawn_any_ = true;
  drawn_level_ = level;
  rest_level_.reset();
  pieces_begun_ = false;
}

void PictureScheduler::piece_drawn(bool completes) {
  if (!completes) return;
  if (focus_left_out_) {  // the whole picture's level with the copy: the refinement goes on from there
    focus_left_out_ = false;
    pieces_begun_ = false;
    return;
  }
  pieces_begun_ = false;
  if (rest_.stage() == RestStage::FullDetail) {
    drawn_level_ = full_detail_step();
    if (drawn_level_ != *rest_level_) return;  // a level on the way: the stage goes on to the next
  } else {
    drawn_level_ = *rest_level_;
  }
  rest_.stage_complete();
}

std::optional<std::uint32_t> PictureScheduler::level_on_the_way() const {
  if (!rest_level_ || focus_left_out_ || rest_.stage() != RestStage::FullDetail) return std::nullopt;
  const std::uint32_t step = full_detail_step();
  if (step == *rest_level_) return std::nullopt;
  return step;
}

std::uint32_t PictureScheduler::full_detail_step() const {
  return drawn_level_ > *rest_level_ + 1 ? drawn_level_ - 1 : *rest_level_;
}

void PictureScheduler::set_exact_when_still(bool on) {
  if (on == rest_.exact_when_still()) return;
  rest_.set_exact_when_still(on);
  pieces_begun_ = false;
}

}  // namespace vxl::app
