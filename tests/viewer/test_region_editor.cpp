// The window's selection regions (region_editor.h): command-line regions become editable spheres or fixed
// masks and boxes; adding, moving, resizing, switching and removing change the criteria and the revision.
#include <gtest/gtest.h>

#include "format/base/error.h"
#include "viewer/app/region_editor.h"

namespace vxl::app {
namespace {

TEST(RegionEditor, CommandLineRegionsAndWindowSpheresMakeTheCriteria) {
  ViewerOptions o;
  o.include = {"1,2,3,4"};
  o.exclude = {"box:0,0,0,1,1,1"};
  RegionEditor e(o);
  ASSERT_EQ(e.regions().size(), 2u);
  EXPECT_TRUE(e.regions()[0].centre.has_value());  // a given sphere can be moved
  EXPECT_FALSE(e.regions()[1].centre.has_value());
  EXPECT_EQ(e.active(), 1u);
  const std::uint64_t r0 = e.revision();

  e.add_sphere({10, 20, 30});
  EXPECT_EQ(e.active(), 2u);
  EXPECT_NE(e.revision(), r0);
  SelectionCriteria c = e.criteria();
  ASSERT_EQ(c.include.size(), 2u);
  ASSERT_EQ(c.exclude.size(), 1u);
  const float inside[3] = {10, 20, 39.9f}, outside[3] = {10, 20, 40.1f};
  EXPECT_TRUE(c.include[1].contains(inside));  // 10 mm by default
  EXPECT_FALSE(c.include[1].contains(outside));

  e.scale_radius(1.25);  // 12.5 mm
  e.move_active_to({10, 20, 28});
  c = e.criteria();
  EXPECT_TRUE(c.include[1].contains(outside));
  EXPECT_EQ(e.regions()[2].argument(), "10.000,20.000,28.000,12.500");

  e.toggle_role();
  c = e.criteria();
  EXPECT_EQ(c.include.size(), 1u);
  EXPECT_EQ(c.exclude.size(), 2u);

  // The per-region counts come back in the criteria's order: includes, ends-in, excludes.
  e.set_counts({7, 8, 9});
  EXPECT_EQ(e.regions()[0].streamlines, 7u);
  EXPECT_EQ(e.regions()[1].streamlines, 8u);
  EXPECT_EQ(e.regions()[2].streamlines, 9u);

  e.remove_active();
  EXPECT_EQ(e.regions().size(), 2u);
  EXPECT_EQ(e.active(), 1u);
  e.activate(0);
  e.move_active_to({0, 0, 0});
  EXPECT_EQ(e.regions()[0].argument(), "0.000,0.000,0.000,4.000");
  e.activate(1);
  const std::uint64_t before = e.revision();
  e.move_active_to({5, 5, 5});  // a box does not move
  e.set_radius(3);
  EXPECT_EQ(e.revision(), before);
  e.remove_active();
  e.remove_active();
  EXPECT_TRUE(e.empty());
  EXPECT_FALSE(e.active().has_value());
}

TEST(RegionEditor, ABadRegionIsRefusedNamingIt) {
  ViewerOptions o;
  o.include = {"1,2,3,-4"};
  try {
    RegionEditor e(o);
    ADD_FAILURE() << "a negative radius was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("1,2,3,-4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vxl::app
