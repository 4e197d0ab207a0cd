// The window's refinement at rest (rest_refinement.h): which stage follows which.
#include <gtest/gtest.h>

#include "viewer/app/rest_refinement.h"

namespace vxl::app {
namespace {

TEST(RestRefinement, ACoarsePictureIsRefinedToFullDetailThenExact) {
  RestRefinement r(/*exact_available=*/true, /*exact_when_still=*/true);
  r.drawn_whole(RenderMode::Axis, /*full_detail=*/false);
  EXPECT_EQ(r.stage(), RestStage::FullDetail);
  EXPECT_EQ(r.stage_mode(), RenderMode::Axis);
  EXPECT_EQ(r.describe(0.4), "refining to full detail: 40 %");
  EXPECT_EQ(r.describe(0.25, 2), "refining to full detail: level 2, 25 %");
  r.stage_complete();
  EXPECT_EQ(r.stage(), RestStage::Exact);
  EXPECT_EQ(r.stage_mode(), RenderMode::Exact);
  EXPECT_EQ(r.describe(0.125), "exact when still: 12 %");
  r.stage_complete();
  EXPECT_EQ(r.stage(), RestStage::Done);
  EXPECT_EQ(r.describe(1), "exact (the camera is still)");
  // Anything drawn whole again starts over.
  r.drawn_whole(RenderMode::Basic, true);
  EXPECT_EQ(r.stage(), RestStage::Exact);
  EXPECT_EQ(r.describe(0), "exact when still: 0 %");
}

TEST(RestRefinement, ExactOnlyFollowsTheModesItIsTheReferenceOf) {
  RestRefinement r(true, true);
  for (RenderMode m : {RenderMode::Unsorted, RenderMode::Additive, RenderMode::Wboit, RenderMode::Opaque}) {
    r.drawn_whole(m, false);
    EXPECT_EQ(r.stage(), RestStage::FullDetail) << render_mode_name(m);
    EXPECT_EQ(r.stage_mode(), m);
    r.stage_complete();
    EXPECT_EQ(r.stage(), RestStage::Done) << render_mode_name(m) << " is shown as chosen, not replaced by exact";
    EXPECT_EQ(r.describe(1), "");
  }
  r.drawn_whole(RenderMode::Exact, true);
  EXPECT_EQ(r.stage(), RestStage::Done) << "the exact mode's own full-detail picture needs nothing more";
}

TEST(RestRefinement, WithoutGl43OrWhenTurnedOffFullDetailIsTheEnd) {
  RestRefinement no_gl43(false, true);
  no_gl43.drawn_whole(RenderMode::Axis, false);
  no_gl43.stage_complete();
  EXPECT_EQ(no_gl43.stage(), RestStage::Done);
  RestRefinement off(true, false);
  off.drawn_whole(RenderMode::Axis, true);
  EXPECT_EQ(off.stage(), RestStage::Done);
  EXPECT_FALSE(off.exact_when_still());
}

TEST(RestRefinement, TurningExactWhenStillOnAndOffAtRest) {
  RestRefinement r(true, false);
  r.drawn_whole(RenderMode::Axis, true);
  ASSERT_EQ(r.stage(), RestStage::Done);
  r.set_exact_when_still(true);  // on at rest: go on to exact
  EXPECT_EQ(r.stage(), RestStage::Exact);
  r.set_exact_when_still(false);  // off before it is shown: the full-detail picture stays
  EXPECT_EQ(r.stage(), RestStage::Done);
  r.set_exact_when_still(true);
  r.stage_complete();
  ASSERT_EQ(r.describe(1), "exact (the camera is still)");
  r.set_exact_when_still(false);  // off once shown: the axis picture is drawn again
  EXPECT_EQ(r.stage(), RestStage::FullDetail);
  EXPECT_EQ(r.stage_mode(), RenderMode::Axis);
  r.stage_complete();
  EXPECT_EQ(r.stage(), RestStage::Done);
  EXPECT_EQ(r.describe(1), "");
}

}  // namespace
}  // namespace vxl::app
