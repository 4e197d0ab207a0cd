#include "viewer/app/window_size.h"

#include <gtest/gtest.h>

namespace vxl::app {
namespace {

TEST(WindowSize, TheDefaultWindowFitsALaptopScreen) {
  // 1024x1024 on a 1280x800 screen whose work area is 1280x770 (a 30-pixel panel).
  const auto size = fit_to_work_area(1024, 1024, 1280, 770);
  EXPECT_EQ(size[0], size[1]);  // the aspect is kept
  EXPECT_LE(size[1], 770 * kWindowShareOfWorkArea);
  EXPECT_GE(size[1], 770 * kWindowShareOfWorkArea - 1);
}

TEST(WindowSize, AWindowThatFitsIsKeptAndAnUnknownScreenChangesNothing) {
  EXPECT_EQ(fit_to_work_area(1024, 1024, 2560, 1400), (std::array<int, 2>{1024, 1024}));
  EXPECT_EQ(fit_to_work_area(1024, 1024, 0, 0), (std::array<int, 2>{1024, 1024}));
  const auto wide = fit_to_work_area(1600, 900, 1000, 1000);
  EXPECT_EQ(wide[0], 900);
  EXPECT_EQ(wide[1], 506);
}

}  // namespace
}  // namespace vxl::app
