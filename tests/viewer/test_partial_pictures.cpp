// The window's partial pictures at rest (partial_pictures.h): when the spans of a level still uploading are shown
// with the level on screen standing in for the others, and how long such a picture is expected to take.
#include <gtest/gtest.h>

#include "viewer/app/partial_pictures.h"

namespace vxl::app {
namespace {

TEST(PartialPictures, AutoWaitsUntilTheUploadHasTakenAsLongAsThePartialPictureWould) {
  PartialPictureRule rule(PartialPictures::Auto);
  rule.picture_shown();  // a coarse picture drawn whole
  rule.uploaded(15);
  rule.uploaded(15);
  EXPECT_TRUE(rule.spans_arrived(2));
  EXPECT_FALSE(rule.wants_picture(2, 40)) << "30 ms of upload: a 40 ms picture now would take more than half the wait";
  rule.uploaded(10);
  EXPECT_TRUE(rule.wants_picture(2, 40));
  EXPECT_FALSE(rule.spans_arrived(0));
  EXPECT_FALSE(rule.wants_picture(0, 0)) << "nothing of the level is in yet";

  // The partial picture drew the view's 2 spans in then: the next one waits for new spans and its own time.
  rule.picture_shown(2);
  rule.uploaded(70);
  EXPECT_FALSE(rule.spans_arrived(2));
  EXPECT_FALSE(rule.wants_picture(2, 60)) << "no span arrived since";
  EXPECT_TRUE(rule.wants_picture(3, 60));
  EXPECT_FALSE(rule.wants_picture(3, 80)) << "a larger picture waits longer";
  rule.picture_shown(3);
  rule.uploaded(59);
  EXPECT_FALSE(rule.wants_picture(5, 60));
}

TEST(PartialPictures, AWholePictureOrACompleteLevelStartsOver) {
  PartialPictureRule rule(PartialPictures::Auto);
  rule.picture_shown(5);
  rule.uploaded(20);
  EXPECT_FALSE(rule.wants_picture(5, 10));
  // A picture drawn whole (the camera moved) shows nothing of the uploading level: its spans in count as new.
  rule.picture_shown();
  EXPECT_FALSE(rule.wants_picture(5, 10)) << "the upload time starts over too";
  rule.uploaded(20);
  EXPECT_TRUE(rule.wants_picture(5, 10));
}

TEST(PartialPictures, AlwaysShowsEveryArrivalAndNeverNone) {
  PartialPictureRule always(PartialPictures::Always), never(PartialPictures::Never);
  EXPECT_TRUE(always.wants_picture(1, 1e9));
  EXPECT_FALSE(never.spans_arrived(1));
  never.uploaded(1e9);
  EXPECT_FALSE(never.wants_picture(1000, 0));
  always.picture_shown(1);
  EXPECT_FALSE(always.wants_picture(1, 0)) << "no span arrived since";
}

TEST(PartialPictures, APartialPictureTakesTheSegmentsInAndTheStandInsShareOfTheRest) {
  // A quarter of the level's 800k segments in the view is in; the coarse picture of the view has 100k: 200k + 75k.
  EXPECT_DOUBLE_EQ(partial_picture_ms(200'000, 800'000, 100'000, 1000), 275.0);
  EXPECT_DOUBLE_EQ(partial_picture_ms(800'000, 800'000, 100'000, 1000), 800.0) << "all in: the level alone";
  EXPECT_DOUBLE_EQ(partial_picture_ms(0, 800'000, 100'000, 1000), 100.0) << "none in: the stand-in alone";
  EXPECT_DOUBLE_EQ(partial_picture_ms(0, 0, 100'000, 1000), 0.0) << "no spans in the view";
  EXPECT_GT(partial_picture_ms(1, 1, 0, 0), 1e6) << "no rate measured: expected to take very long, not to divide by 0";
}

}  // namespace
}  // namespace vxl::app
