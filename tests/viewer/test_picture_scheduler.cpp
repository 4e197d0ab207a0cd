// What the window draws each frame (picture_scheduler.h): a changed picture whole (the first at the first
// picture's level, then at the frame budget's level, a script's last at the scene's level), an unchanged
// one refined at rest to the view's level and then to exact, nothing once refined or when closing.
#include <gtest/gtest.h>

#include "viewer/app/picture_scheduler.h"

namespace vxl::app {
namespace {

constexpr std::uint32_t kSceneLevel = 1, kCoarsest = 3, kFirstLevel = 2;

PictureScheduler scheduler(bool gl43, double budget_ms = 100, bool forced = false) {
  return PictureScheduler(FrameBudget(budget_ms, kSceneLevel, kCoarsest), RestRefinement(gl43, true), kSceneLevel,
                          forced, kFirstLevel);
}

// A level_for_view that counts how often it is asked.
struct ViewLevel {
  std::uint32_t level;
  int asked = 0;
  std::function<std::uint32_t()> fn() {
    return [this] {
      ++asked;
      return level;
    };
  }
};

TEST(PictureScheduler, AChangedPictureIsDrawnWholeAtTheFirstThenTheBudgetsLevel) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{0};
  PictureTask t = s.next(true, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Whole);
  EXPECT_EQ(t.level, kFirstLevel) << "the first picture comes at once";
  s.drawn_whole(RenderMode::Axis, t.level, 40);
  t = s.next(true, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Whole);
  EXPECT_EQ(t.level, 2u) << "level 1 would take about 8 x 40 ms, beyond the 100 ms budget";
  s.drawn_whole(RenderMode::Axis, t.level, 5);
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, kSceneLevel) << "8 x 5 ms fits";
  t = s.next(false, true, true, view.fn());
  EXPECT_EQ(t.work, PictureWork::Whole);
  EXPECT_EQ(t.level, kSceneLevel) << "a script's last frame is drawn at the scene's level";
  EXPECT_EQ(view.asked, 0) << "the view's level is asked only at rest";
}

// The first picture also builds the shaders and draws from new buffers: its time decides the level only until a
// whole picture is measured, so that a level it put over the budget is tried again when a measured one fits it.
TEST(PictureScheduler, TheFirstPicturesTimeDecidesOnlyUntilAPictureIsMeasured) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{0};
  s.drawn_whole(RenderMode::Axis, s.next(true, false, false, view.fn()).level, 150);  // level 2, over the budget
  PictureTask t = s.next(true, false, false, view.fn());
  EXPECT_EQ(t.level, kCoarsest) << "nothing measured yet: level 2 as the first picture cost it";
  s.drawn_whole(RenderMode::Axis, t.level, 5);
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, kFirstLevel) << "8 x 5 ms fits: level 2 is tried again";
  s.drawn_whole(RenderMode::Axis, kFirstLevel, 150);
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, kCoarsest) << "measured over the budget";
}

// While a selection is made on the other cores, whole pictures are measured and chosen under that load.
TEST(PictureScheduler, WholePicturesAreMeasuredAndChosenUnderTheirLoad) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{0};
  s.drawn_whole(RenderMode::Axis, s.next(true, false, false, view.fn()).level, 40);  // level 2, idle
  s.drawn_whole(RenderMode::Axis, 2, 5);
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, kSceneLevel);
  s.set_load({false, true});
  s.drawn_whole(RenderMode::Axis, 2, 20);  // a selection on its way: four times the cost
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, 2u) << "level 1 would take 8 x 20 ms while it runs";
  s.set_load({});
  EXPECT_EQ(s.next(true, false, false, view.fn()).level, kSceneLevel) << "idle again: 8 x 5 ms fits";
}

// A whole picture that left the focus's full-detail copy out (it does not fit the frame budget) is drawn again with
// it first, in pieces at its own level; then the refinement goes on to the view's level.
TEST(PictureScheduler, AFocusCopyLeftOutOfAWholePictureComesFirstAtRest) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{kSceneLevel};
  s.drawn_whole(RenderMode::Axis, kCoarsest, 40, true);
  EXPECT_TRUE(s.focus_stage());
  PictureTask t = s.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Piece);
  EXPECT_EQ(t.level, kCoarsest) << "the whole picture's level, with the copy";
  EXPECT_EQ(t.frame_work, FrameWork::FocusPiece);
  EXPECT_EQ(view.asked, 0);
  s.begin_pieces();
  s.piece_drawn(false);
  EXPECT_TRUE(s.focus_stage());
  s.piece_drawn(true);
  EXPECT_FALSE(s.focus_stage());
  EXPECT_FALSE(s.pieces_begun()) << "the full-detail stage begins its own pieces";
  EXPECT_EQ(s.drawn_level(), kCoarsest);
  t = s.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Piece);
  EXPECT_EQ(t.level, kCoarsest - 1) << "on the way to the view's level";
  EXPECT_EQ(t.frame_work, FrameWork::FullDetailPiece);
  // A picture drawn whole with the copy (or without a focus) has no such stage; a change drops it.
  s.drawn_whole(RenderMode::Axis, kCoarsest, 40, true);
  s.drawn_whole(RenderMode::Axis, kCoarsest, 40);
  EXPECT_FALSE(s.focus_stage());
  EXPECT_EQ(s.next(false, false, false, view.fn()).frame_work, FrameWork::FullDetailPiece);
  s.drawn_whole(RenderMode::Axis, kCoarsest, 40, true);
  EXPECT_EQ(s.next(false, false, true, view.fn()).work, PictureWork::None) << "closing: nothing refined";
}

// Through each level between the picture on screen and the view's, each shown once complete.
TEST(PictureScheduler, AtRestACoarsePictureIsRefinedAtTheViewsLevelThenToExact) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{0};  // a slab: full detail fits
  s.drawn_whole(RenderMode::Axis, kFirstLevel, 10);
  PictureTask t = s.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Piece);
  EXPECT_EQ(t.level, 1u) << "level 1 on the way to 0";
  EXPECT_EQ(s.level_on_the_way(), 1u);
  EXPECT_EQ(t.frame_work, FrameWork::FullDetailPiece);
  EXPECT_EQ(s.rest().stage_mode(), RenderMode::Axis);
  s.begin_pieces();
  s.piece_drawn(false);
  EXPECT_TRUE(s.pieces_begun());
  EXPECT_EQ(s.next(false, false, false, view.fn()).level, 1u);
  s.piece_drawn(true);
  EXPECT_FALSE(s.pieces_begun()) << "the view's level begins its own pieces";
  EXPECT_EQ(s.drawn_level(), 1u);
  EXPECT_EQ(s.rest().stage(), RestStage::FullDetail);
  t = s.next(false, false, false, view.fn());
  EXPECT_EQ(t.level, 0u);
  EXPECT_EQ(t.frame_work, FrameWork::FullDetailPiece);
  EXPECT_EQ(s.level_on_the_way(), std::nullopt) << "the view's level itself";
  s.begin_pieces();
  s.piece_drawn(true);
  EXPECT_FALSE(s.pieces_begun()) << "the next stage begins its own pieces";
  EXPECT_EQ(s.drawn_level(), 0u);
  t = s.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Piece);
  EXPECT_EQ(t.frame_work, FrameWork::ExactPiece);
  EXPECT_EQ(s.rest().stage_mode(), RenderMode::Exact);
  s.piece_drawn(true);
  EXPECT_EQ(s.next(false, false, false, view.fn()).work, PictureWork::None) << "refined";
  EXPECT_EQ(view.asked, 1) << "once per picture drawn whole";
  s.drawn_whole(RenderMode::Axis, kSceneLevel, 10);
  s.next(false, false, false, view.fn());
  EXPECT_EQ(view.asked, 2) << "a new picture asks again";
}

// Only levels strictly between the picture's and the view's are drawn on the way, and only once the refinement has
// chosen the view's level, outside the focus stage.
TEST(PictureScheduler, OnlyLevelsStrictlyBetweenArePutOnTheWay) {
  PictureScheduler s = scheduler(true);
  ViewLevel full{0};
  s.drawn_whole(RenderMode::Axis, 1, 10);
  EXPECT_EQ(s.level_on_the_way(), std::nullopt) << "the view's level is not chosen yet";
  EXPECT_EQ(s.next(false, false, false, full.fn()).level, 0u) << "one level above the view's: straight to it";
  EXPECT_EQ(s.level_on_the_way(), std::nullopt);
  // A picture finer than the view's level (a close view's, say, then moved back) is drawn again at the view's.
  ViewLevel coarse{2};
  s.drawn_whole(RenderMode::Axis, 1, 10);
  EXPECT_EQ(s.next(false, false, false, coarse.fn()).level, 2u);
  EXPECT_EQ(s.level_on_the_way(), std::nullopt);
  // The focus stage draws the whole picture's level with the copy; the steps come after it.
  s.drawn_whole(RenderMode::Axis, kCoarsest, 40, true);
  EXPECT_EQ(s.next(false, false, false, full.fn()).frame_work, FrameWork::FocusPiece);
  EXPECT_EQ(s.level_on_the_way(), std::nullopt);
}

TEST(PictureScheduler, APictureAlreadyAtTheViewsLevelSkipsTheFullDetailStage) {
  PictureScheduler without_gl43 = scheduler(false);
  ViewLevel view{kSceneLevel};
  without_gl43.drawn_whole(RenderMode::Axis, kSceneLevel, 10);
  PictureTask t = without_gl43.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::None);
  EXPECT_TRUE(t.stage_skipped);
  EXPECT_EQ(without_gl43.rest().stage(), RestStage::Done);

  PictureScheduler with_gl43 = scheduler(true);
  with_gl43.drawn_whole(RenderMode::Basic, kSceneLevel, 10);
  t = with_gl43.next(false, false, false, view.fn());
  EXPECT_EQ(t.work, PictureWork::Piece);
  EXPECT_EQ(t.frame_work, FrameWork::ExactPiece) << "straight on to exact";
  EXPECT_EQ(t.level, kSceneLevel);
}

TEST(PictureScheduler, FullDetailAndAForcedLevelNeedNoRefinementAndClosingDrawsNothing) {
  ViewLevel view{0};
  PictureScheduler s = scheduler(false);
  s.drawn_whole(RenderMode::Axis, 0, 10);
  EXPECT_EQ(s.next(false, false, false, view.fn()).work, PictureWork::None);
  PictureScheduler forced = scheduler(false, 100, true);
  forced.drawn_whole(RenderMode::Axis, kSceneLevel, 10);
  EXPECT_EQ(forced.rest().stage(), RestStage::Done) << "--level's picture is the full one";
  PictureScheduler closing = scheduler(true);
  closing.drawn_whole(RenderMode::Axis, kFirstLevel, 10);
  EXPECT_EQ(closing.next(false, false, true, view.fn()).work, PictureWork::None);
  EXPECT_EQ(view.asked, 0);
}

TEST(PictureScheduler, TurningExactWhenStillOffAbandonsItsPieces) {
  PictureScheduler s = scheduler(true);
  ViewLevel view{0};
  s.drawn_whole(RenderMode::Axis, 0, 10);
  ASSERT_EQ(s.next(false, false, false, view.fn()).frame_work, FrameWork::ExactPiece);
  s.begin_pieces();
  s.set_exact_when_still(true);
  EXPECT_TRUE(s.pieces_begun()) << "no change, the pieces go on";
  s.set_exact_when_still(false);
  EXPECT_FALSE(s.pieces_begun());
  EXPECT_EQ(s.next(false, false, false, view.fn()).work, PictureWork::None);
  s.drawn_whole(RenderMode::Axis, kFirstLevel, 10);
  s.begin_pieces();
  s.drawn_whole(RenderMode::Axis, kFirstLevel, 10);
  EXPECT_FALSE(s.pieces_begun()) << "a whole picture abandons them";
}

}  // namespace
}  // namespace vxl::app
