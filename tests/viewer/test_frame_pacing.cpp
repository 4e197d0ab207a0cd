#include "viewer/app/frame_pacing.h"

#include <gtest/gtest.h>

namespace vxl::app {
namespace {

TEST(FramePacing, DrawsAFrameAfterInputBeforeSleeping) {
  FramePacing pacing;
  pacing.frame_started(true);
  pacing.frame_ended(false, false);
  EXPECT_FALSE(pacing.may_wait());  // ImGui shows the click in the next frame
  pacing.frame_started(false);
  pacing.frame_ended(false, false);
  EXPECT_FALSE(pacing.may_wait());
  pacing.frame_started(false);
  pacing.frame_ended(false, false);
  EXPECT_TRUE(pacing.may_wait());
}

TEST(FramePacing, KeepsDrawingWhileTheRefinementHasPieces) {
  FramePacing pacing;
  for (int piece = 0; piece < 10; ++piece) {
    pacing.frame_started(false);
    pacing.frame_ended(true, true);
    EXPECT_FALSE(pacing.may_wait()) << "piece " << piece;
  }
}

TEST(FramePacing, ThePieceThatCompletesTheRefinementIsFollowedByAFrameThatShowsIt) {
  FramePacing pacing;
  for (int i = 0; i < 3; ++i) {  // input settles
    pacing.frame_started(false);
    pacing.frame_ended(true, true);
  }
  // The last piece: the refinement is done, but the panel was built before the piece (it still shows the
  // previous percentage), so the window must not sleep yet.
  pacing.frame_started(false);
  pacing.frame_ended(false, true);
  EXPECT_FALSE(pacing.may_wait());
  // That frame builds the panel from the final state and draws nothing new: now it may sleep.
  pacing.frame_started(false);
  pacing.frame_ended(false, false);
  EXPECT_TRUE(pacing.may_wait());
}

// A selection or focus copy made off the window's thread sends no event when it is done: an idle window must not
// sleep until the next input while one is in flight, or the picture would wait for the user to move.
TEST(FramePacing, AnIdleWindowLooksAgainWhileWorkIsInFlight) {
  FramePacing pacing;
  for (int i = 0; i < 3; ++i) {
    pacing.frame_started(false);
    pacing.frame_ended(false, false);
  }
  ASSERT_TRUE(pacing.may_wait());
  EXPECT_EQ(pacing.next_wait(false, false), FramePacing::Wait::UntilInput);
  EXPECT_EQ(pacing.next_wait(false, true), FramePacing::Wait::Briefly);
  EXPECT_EQ(pacing.next_wait(true, true), FramePacing::Wait::None);  // a script never waits
  pacing.frame_started(true);                                        // input: frames follow at once
  EXPECT_EQ(pacing.next_wait(false, true), FramePacing::Wait::None);
}

}  // namespace
}  // namespace vxl::app
