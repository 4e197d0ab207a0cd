// The window's partial pictures at rest (partial_pictures.h): when the spans of a level still uploading are shown
// with the level on screen standing in for the others.
#include <gtest/gtest.h>

#include "viewer/app/partial_pictures.h"

namespace vxl::app {
namespace {

TEST(PartialPictures, AutoWaitsUntilTheUploadHasTakenAsLongAsThePictureOnScreenTookToDraw) {
  PartialPictureRule rule(PartialPictures::Auto);
  rule.picture_shown(40);  // a coarse picture drawn whole in 40 ms
  rule.uploaded(15);
  rule.uploaded(15);
  EXPECT_FALSE(rule.wants_picture(1000)) << "30 ms of upload: drawing now would take more than half the wait";
  rule.uploaded(10);
  EXPECT_TRUE(rule.wants_picture(1000));
  EXPECT_FALSE(rule.wants_picture(0)) << "nothing of the level is in yet";

  // The partial picture drew the 1000 bytes in then, in 60 ms: the next one waits for 60 ms of upload and new spans.
  rule.picture_shown(60, 1000);
  rule.uploaded(70);
  EXPECT_FALSE(rule.wants_picture(1000)) << "no span arrived since";
  EXPECT_TRUE(rule.wants_picture(1500));
  rule.picture_shown(60, 1500);
  rule.uploaded(59);
  EXPECT_FALSE(rule.wants_picture(3000));
}

TEST(PartialPictures, AWholePictureOrACompleteLevelStartsOver) {
  PartialPictureRule rule(PartialPictures::Auto);
  rule.picture_shown(10, 5000);
  rule.uploaded(20);
  EXPECT_FALSE(rule.wants_picture(5000));
  // A picture drawn whole (the camera moved) shows nothing of the uploading level: what is in counts as new.
  rule.picture_shown(10);
  rule.uploaded(20);
  EXPECT_TRUE(rule.wants_picture(5000));
}

TEST(PartialPictures, AlwaysShowsEveryArrivalAndNeverNone) {
  PartialPictureRule always(PartialPictures::Always), never(PartialPictures::Never);
  for (PartialPictureRule* rule : {&always, &never}) {
    rule->picture_shown(1000);
    rule->uploaded(1);
  }
  EXPECT_TRUE(always.wants_picture(1));
  EXPECT_FALSE(never.wants_picture(1));
  always.picture_shown(1000, 1);
  EXPECT_FALSE(always.wants_picture(1)) << "no span arrived since";
  never.uploaded(1e9);
  EXPECT_FALSE(never.wants_picture(1u << 30));
}

}  // namespace
}  // namespace vxl::app
