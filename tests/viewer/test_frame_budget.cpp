// The window's frame budget and its statistics (voxview --frame-budget, --stats), without a window.
#include <gtest/gtest.h>

#include "viewer/app/frame_budget.h"
#include "viewer/app/frame_log.h"

namespace vxl::app {
namespace {

TEST(FrameBudget, AtRestOrWithoutABudgetTheScenesLevel) {
  FrameBudget budget(100, 1, 4);
  budget.record(1, 5000);
  EXPECT_EQ(budget.level_for(false), 1u);
  EXPECT_EQ(FrameBudget(0, 1, 4).level_for(true), 1u);
}

TEST(FrameBudget, MovingPicksTheFinestLevelWhoseCostFits) {
  FrameBudget budget(100, 0, 4);
  EXPECT_EQ(budget.level_for(true), 0u) << "nothing measured: try the scene's level";
  budget.record(0, 800);  // level 1 is estimated at 100 ms: fits exactly
  EXPECT_DOUBLE_EQ(budget.estimate_ms(1), 100.0);
  EXPECT_EQ(budget.level_for(true), 1u);
  budget.record(1, 150);  // measured slower than estimated: one level coarser
  EXPECT_EQ(budget.level_for(true), 2u);
  EXPECT_DOUBLE_EQ(budget.estimate_ms(2), 150.0 / 8);
  budget.record(0, 1e9);
  budget.record(1, 1e8);
  budget.record(2, 1e7);
  EXPECT_EQ(budget.level_for(true), 4u) << "nothing fits: the coarsest level";
}

// The first picture also pays for the shaders built and the buffers first drawn from: on llvmpipe a 1M set's level
// 3 took 100-106 ms as the first picture and 44-77 ms a frame after. It decides only until a frame is measured.
TEST(FrameBudget, TheFirstPictureCountsOnlyUntilAFrameIsMeasured) {
  FrameBudget budget(100, 0, 4);
  budget.record_first_picture(3, 105);
  EXPECT_DOUBLE_EQ(budget.estimate_ms(4), 105.0 / 8);
  EXPECT_EQ(budget.level_for(true), 4u) << "nothing else known: level 3 as the first picture cost it";
  budget.record(4, 18);  // the level's own first frame
  EXPECT_EQ(budget.level_for(true), 4u) << "8 x 18 ms";
  budget.record(4, 9.8);
  EXPECT_DOUBLE_EQ(budget.estimate_ms(3), 9.8 * 8);
  EXPECT_EQ(budget.level_for(true), 3u) << "measured frames put it within the budget";
  budget.record(3, 105);
  EXPECT_EQ(budget.level_for(true), 4u) << "measured over the budget: not tried again";
}

TEST(FrameBudget, NeverFinerThanTheSceneNorCoarserThanTheFile) {
  FrameBudget budget(10, 2, 3);
  budget.record(2, 5);
  EXPECT_EQ(budget.level_for(true), 2u);
  budget.record(2, 1000);
  EXPECT_EQ(budget.level_for(true), 3u);
  FrameBudget single(10, 0, 0);  // a file without levels
  single.record(0, 1000);
  EXPECT_EQ(single.level_for(true), 0u);
}

// A selection being made on the other cores slows the drawing down: frames under it are measured apart, so
// that the level chosen while it runs fits the budget, and the one chosen once it is done is not held back.
TEST(FrameBudget, EachLoadIsMeasuredApart) {
  FrameBudget budget(100, 0, 4);
  const FrameLoad idle, selecting{false, true};
  budget.record(1, 60, idle);
  budget.record(1, 150, selecting);
  EXPECT_EQ(budget.level_for(true, idle), 1u);
  EXPECT_EQ(budget.level_for(true, selecting), 2u);
  budget.record(1, 70, idle);  // a later idle frame does not replace what the selection costs
  EXPECT_EQ(budget.level_for(true, selecting), 2u);
  EXPECT_DOUBLE_EQ(budget.estimate_ms(1, selecting), 150.0);
}

// A load not measured at a level: another load's cost there, scaled by what the two cost where both were
// measured (the focus drawn beside the context costs its own segments at every level).
TEST(FrameBudget, AnUnmeasuredLoadIsScaledByTheLoadsRatio) {
  FrameBudget budget(100, 0, 4);
  const FrameLoad idle, with_focus{true, false};
  budget.record(2, 10, idle);
  budget.record(2, 20, with_focus);
  budget.record(1, 60, idle);
  EXPECT_DOUBLE_EQ(budget.estimate_ms(1, with_focus), 120.0)
      << "level 1 measured without the focus, twice dearer with it";
  EXPECT_EQ(budget.level_for(true, with_focus), 2u);
  EXPECT_EQ(budget.level_for(true, idle), 1u);

  FrameBudget first_frames(100, 0, 4);
  first_frames.record(1, 60, idle);
  EXPECT_DOUBLE_EQ(first_frames.estimate_ms(1, {true, true}), 60.0) << "no ratio known yet: unscaled";
  first_frames.record(1, 90, {false, true});
  first_frames.record(1, 200, {true, false});
  EXPECT_DOUBLE_EQ(first_frames.estimate_ms(0, {true, true}), 200.0 * 8) << "one load away before two";
}

TEST(FrameBudget, TheFirstPictureIsTheFinestLevelOfAtMostAQuarterMillionSegments) {
  // The 1M set's levels: level 2's 870k segments take 1-3 s on llvmpipe, too long for the first picture.
  const std::uint64_t segments[] = {55'000'000, 7'000'000, 870'000, 110'000, 14'000};
  EXPECT_EQ(first_picture_level(segments, 0), 3u);
  EXPECT_EQ(first_picture_level(segments, 4), 4u) << "never finer than the scene's level";
  const std::uint64_t at_the_limit[] = {1'000'000, 250'000};
  EXPECT_EQ(first_picture_level(at_the_limit, 0), 1u);
  const std::uint64_t small[] = {200'000, 50'000};
  EXPECT_EQ(first_picture_level(small, 0), 0u) << "a small scene comes at full detail at once";
  const std::uint64_t huge[] = {9'000'000'000, 1'000'000'000, 200'000'000};
  EXPECT_EQ(first_picture_level(huge, 0), 2u) << "nothing small enough: the coarsest";
  EXPECT_EQ(first_picture_level({}, 1), 1u);
}

TEST(FrameLog, SummaryGivesTheFirstAndFullDetailPicturesAndMovingPercentiles) {
  std::vector<FrameRecord> frames = {{2, false, 50, 0.4}, {0, false, 900, 1.3}};
  for (int i = 1; i <= 20; ++i) frames.push_back({1, true, double(i), 1.3 + 0.1 * i});
  const FrameSummary s = summarize_frames(frames, 0);
  EXPECT_DOUBLE_EQ(s.first_picture_s, 0.4);
  EXPECT_DOUBLE_EQ(s.full_detail_s, 1.3);
  EXPECT_EQ(s.moving_frames, 20u);
  EXPECT_DOUBLE_EQ(s.moving_median_ms, 10.0);
  EXPECT_DOUBLE_EQ(s.moving_p95_ms, 19.0);
  const FrameSummary none = summarize_frames({}, 0);
  EXPECT_LT(none.first_picture_s, 0.0);
  EXPECT_EQ(none.moving_frames, 0u);
}

// Refinement at rest: pieces count apart from moving frames; full detail is the first complete picture at the
// finest level reached at rest (finer than the scene's level where a view's visible part fits); exact after it.
TEST(FrameLog, RefinementPiecesAndTheFinestLevelReachedAtRest) {
  using W = FrameWork;
  const std::vector<FrameRecord> frames = {{2, false, 40, 0.2, W::Whole, true},
                                           {1, false, 300, 0.6, W::Whole, true},
                                           {0, false, 100, 0.7, W::FullDetailPiece, false},
                                           {0, false, 120, 0.8, W::FullDetailPiece, true},
                                           {0, false, 90, 0.9, W::ExactPiece, false},
                                           {0, false, 110, 1.0, W::ExactPiece, true}};
  const FrameSummary s = summarize_frames(frames, 1);
  EXPECT_DOUBLE_EQ(s.first_picture_s, 0.2);
  EXPECT_DOUBLE_EQ(s.full_detail_s, 0.8) << "level 0 was reached: the level-1 picture was not the finest";
  EXPECT_DOUBLE_EQ(s.exact_s, 1.0);
  EXPECT_EQ(s.pieces, 4u);
  EXPECT_DOUBLE_EQ(s.piece_median_ms, 100.0);
  EXPECT_DOUBLE_EQ(s.piece_p95_ms, 120.0);
  EXPECT_EQ(s.moving_frames, 0u);
  // Without a finer level, the scene's level at rest is full detail.
  EXPECT_DOUBLE_EQ(summarize_frames({frames[0], frames[1]}, 1).full_detail_s, 0.6);
  EXPECT_LT(summarize_frames({frames[0]}, 1).full_detail_s, 0.0) << "only coarser than the scene's level";
}

// A partial picture (a level's spans in so far, the coarser level for the rest) is a piece, but not full detail, even
// at the finest level: full detail is the level's complete picture after it.
TEST(FrameLog, APartialPictureIsNotFullDetail) {
  using W = FrameWork;
  const std::vector<FrameRecord> frames = {{1, false, 40, 0.2, W::Whole, true},
                                           {0, false, 60, 0.5, W::PartialPiece, true},
                                           {0, false, 30, 0.6, W::FullDetailPiece, false},
                                           {0, false, 80, 0.9, W::FullDetailPiece, true}};
  const FrameSummary s = summarize_frames(frames, 0);
  EXPECT_DOUBLE_EQ(s.full_detail_s, 0.9);
  EXPECT_EQ(s.pieces, 3u);
  EXPECT_LT(summarize_frames({frames[0], frames[1]}, 0).full_detail_s, 0.0) << "only the partial picture at level 0";
  // Nor is it the finest level reached: with the scene at level 1 and no complete level-0 picture, full detail is
  // the level-1 picture.
  EXPECT_DOUBLE_EQ(summarize_frames({frames[0], frames[1], frames[2]}, 1).full_detail_s, 0.2);
}

}  // namespace
}  // namespace vxl::app
