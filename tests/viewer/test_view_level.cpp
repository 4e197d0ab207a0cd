// The level one view is drawn at (view_level.h), chosen on the scene's layouts without GL: the finest
// whose visible spans fit the GPU memory budget, the scene's level when none finer fits or --level forces
// it, with the bounds the renderer's projection uses (the lines joined with the image's box).
#include <cstdint>

#include <glm/gtc/matrix_transform.hpp>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "format/vxl_file.h"
#include "tests/test_support.h"
#include "tests/viewer/render_support.h"
#include "viewer/app/view_level.h"

namespace vxl::app {
namespace {

using test::ScratchDir;

class ViewLevel : public ::testing::Test {
 protected:
  void SetUp() override {
    SynthSettings synth;
    synth.streamlines = 6000;
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = 3;
    convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
    file.emplace(VxlFile::open(dir.file("scene.vxl")));
  }
  std::vector<const VxlFile*> files() const { return {&*file}; }
  // Small spans, so that a slab touches only some of them at every level.
  std::uint64_t span_texels() const { return SceneLayout::largest_voxel_texels(files()); }
  static Camera view() { return test::synth_brain_view(); }
  static Clipping slab() {
    Clipping c;
    c.slab_mm = 6;
    return c;
  }
  ScratchDir dir;
  std::optional<VxlFile> file;
};

TEST_F(ViewLevel, TheFinestLevelWhoseVisiblePartFitsIsChosen) {
  LevelLayouts layouts(files(), span_texels());
  const SceneBounds bounds = scene_bounds(files(), nullptr);
  const std::uint64_t slab_at_0 = view_bytes(layouts.at(0), view(), 1.0, bounds, slab());
  const std::uint64_t slab_at_1 = view_bytes(layouts.at(1), view(), 1.0, bounds, slab());
  ASSERT_LT(slab_at_0, layouts.at(0).upload_bytes()) << "the slab needs fewer spans than the whole scene";
  ASSERT_LT(slab_at_1, slab_at_0);
  SceneDetail detail;
  detail.level = 2;
  detail.budget = slab_at_0;
  EXPECT_EQ(level_for_view(layouts, detail, view(), 1.0, bounds, slab()), 0u) << "full detail fits exactly";
  detail.budget = slab_at_0 - 1;
  EXPECT_EQ(level_for_view(layouts, detail, view(), 1.0, bounds, slab()), 1u);
  detail.budget = slab_at_1 - 1;
  EXPECT_EQ(level_for_view(layouts, detail, view(), 1.0, bounds, slab()), 2u) << "none finer fits: the scene's";
  detail.forced = true;
  detail.budget = ~std::uint64_t(0);
  EXPECT_EQ(level_for_view(layouts, detail, view(), 1.0, bounds, slab()), 2u) << "--level is kept";
}

TEST_F(ViewLevel, TheImagesBoxJoinsTheLinesBounds) {
  const SceneBounds lines = scene_bounds(files(), nullptr);
  const SceneBounds expected = line_bounds(files());
  EXPECT_EQ(lines.min, expected.min);
  EXPECT_EQ(lines.max, expected.max);
  Volume image;
  image.dims = {10, 10, 10};
  image.voxel_to_ras = glm::translate(glm::dmat4(1.0), glm::dvec3(lines.max.x, 0, 0)) *
                       glm::scale(glm::dmat4(1.0), glm::dvec3(20.0));  // reaches beyond the lines in +x
  const SceneBounds joined = scene_bounds(files(), &image);
  EXPECT_EQ(joined.max.x, image.ras_max().x);
  EXPECT_GT(joined.max.x, lines.max.x);
  EXPECT_EQ(joined.min, glm::min(lines.min, image.ras_min()));
}

}  // namespace
}  // namespace vxl::app
