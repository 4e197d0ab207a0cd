// The `segsort` mode's CPU part (viewer/render/segment_sort.h), without GL: one voxel's segments come out far
// to near for the eye, and the sorter writes every visible voxel's segments, sorted, where the draw reads them.
#include <algorithm>
#include <numeric>

#include "converter/convert/convert.h"
#include "converter/synth/synth.h"
#include "tests/test_support.h"
#include "viewer/render/camera.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/segment_sort.h"

namespace vxl {
namespace {

using test::ScratchDir;

// Five segments (vertex pairs 0-1, 2-3, 4-5, 6-7, 8-9; 1-2 etc. are not segments) along the x axis and off it.
const std::vector<float> kXyz = {
    0,  0,  0, 2,  0,  0,  // 0: midpoint (1, 0, 0)
    10, 0,  0, 12, 0,  0,  // 2: midpoint (11, 0, 0)
    5,  0,  0, 7,  0,  0,  // 4: midpoint (6, 0, 0)
    5,  40, 0, 7,  40, 0,  // 6: midpoint (6, 40, 0): as deep as 4 along x, but far off the axis
    10, 0,  0, 12, 0,  0,  // 8: the same as 2 (a tie)
};
const std::vector<std::uint32_t> kStarts = {0, 2, 4, 6, 8};

std::vector<std::uint32_t> sorted(const SegmentSortView& view, std::uint32_t base = 0) {
  std::vector<std::pair<double, std::uint32_t>> keys;
  std::vector<std::uint32_t> out(kStarts.size(), 0xFFFFFFFFu);
  sort_segments_far_to_near(kXyz, kStarts, view, base, keys, out.data());
  return out;
}

TEST(SegmentSort, SegmentsComeOutFarToNearForTheEye) {
  // Looking along +x from x = -10: the segment at x = 11 (and its twin) is farthest, the one at x = 1 nearest.
  const SegmentSortView ortho{{-10, 0, 0}, {1, 0, 0}, true};
  // Orthographic depth is the projection on the view direction: 4 and 6 tie at 16 mm (4 first: ties keep
  // ascending starts), and so do 2 and 8.
  EXPECT_EQ(sorted(ortho), (std::vector<std::uint32_t>{2, 8, 4, 6, 0}));
  // Perspective depth is the distance to the eye: 6 is 40 mm off the axis, so it is the farthest.
  const SegmentSortView perspective{{-10, 0, 0}, {1, 0, 0}, false};
  EXPECT_EQ(sorted(perspective), (std::vector<std::uint32_t>{6, 2, 8, 4, 0}));
  // From the other side, the order turns round (ties still ascending); `base` offsets every index.
  const SegmentSortView back{{30, 0, 0}, {-1, 0, 0}, true};
  EXPECT_EQ(sorted(back, 100), (std::vector<std::uint32_t>{100, 104, 106, 102, 108}));
  // Deterministic: the same input gives the same output.
  EXPECT_EQ(sorted(perspective), sorted(perspective));
}

// The view of a perspective camera, as the renderer builds it.
ViewParams view_of(const Camera& c) {
  return make_view_params(c.eye(), c.forward(), c.orthographic, glm::dmat4(c.projection(1.0, 1.0, 2000.0)),
                          glm::dmat3(c.view_rotation()));
}

// On a converted scene at a coarse level and at full detail: every voxel the plan draws has its level's
// segments, each once, far to near, at its range of its span's array, and the plan draws those ranges.
TEST(SegmentSort, TheSorterWritesEveryVisibleVoxelsSegmentsFarToNear) {
  ScratchDir dir;
  SynthSettings synth;
  synth.streamlines = 600;
  ConvertSettings settings;
  settings.voxel_size = 15;
  settings.levels = 2;
  const std::string path = dir.file("scene.vxl");
  convert_tractogram(synthesize_tractogram(synth), path, settings);
  const VxlFile file = VxlFile::open(path);
  ASSERT_EQ(file.level_count(), 2u);
  Camera camera;
  camera.azimuth_deg = 35;
  camera.elevation_deg = 20;
  camera.frame({-70, -105, -50}, {70, 70, 70}, 1.0);
  camera.distance *= 0.5;  // close: some voxels fall outside the frustum
  for (std::uint32_t level : {0u, 1u}) {
    SCOPED_TRACE(level);
    // Small texture buffers: several spans.
    const std::uint64_t words = SceneLayout(file, 1u << 27, level).texture_spans()[0].order_words;
    const SceneLayout layout(file, words / 4 + 1, level);
    ASSERT_GT(layout.texture_spans().size(), 2u);
    FramePlan plan;
    plan_frame(layout, view_of(camera), PlanOrder::Block, plan);
    ASSERT_GT(plan.voxels.size(), 5u);
    ASSERT_LT(plan.voxels.size(), file.voxels().size()) << "some voxels are culled";
    SegmentSorter sorter(layout, {&file});
    const SegmentSortView view{camera.eye(), camera.forward(), false};
    sorter.sort(view, plan);
    ASSERT_EQ(plan.first.size(), plan.voxels.size());
    ASSERT_EQ(plan.count.size(), plan.voxels.size());
    std::uint64_t segments = 0;
    std::vector<float> xyz;
    for (std::size_t k = 0; k < plan.voxels.size(); ++k) {
      const std::uint32_t i = plan.voxels[k];
      const VoxelDrawInfo& d = layout.voxels()[i];
      const std::uint32_t li = layout.local_voxel(i);
      EXPECT_EQ(plan.first[k], layout.dataset_id(d.span, d.seg_first));
      EXPECT_EQ(plan.count[k], std::int32_t(2 * d.segment_count));
      ASSERT_EQ(d.segment_count, file.level(li, level).segment_count);
      const auto [first, end] = sorter.written(d.span);
      EXPECT_LE(first, d.seg_first);
      EXPECT_GE(end, d.seg_first + d.segment_count);
      // The voxel's entries: its segments' first vertices (order 0 lists them), each once ...
      const std::uint32_t* entries = sorter.span_order(d.span).data() + d.seg_first;
      std::vector<std::uint32_t> got(entries, entries + d.segment_count), want;
      const OrderView o = file.order(li, 0, level);
      for (std::uint32_t n = 0; n < o.count; ++n) want.push_back(std::uint32_t(d.vertex_first) + o[n]);
      std::sort(got.begin(), got.end());
      std::sort(want.begin(), want.end());
      EXPECT_EQ(got, want);
      // ... far to near.
      xyz.resize(3 * std::uint64_t(d.vertex_count));
      file.read_vertices(li, file.voxels()[li].vertex_first, d.vertex_count, xyz.data());
      for (std::uint32_t n = 0; n + 1 < d.segment_count; ++n) {
        const std::uint64_t a = entries[n] - d.vertex_first, b = entries[n + 1] - d.vertex_first;
        ASSERT_GE(segment_depth(view, &xyz[3 * a], &xyz[3 * a + 3]), segment_depth(view, &xyz[3 * b], &xyz[3 * b + 3]))
            << "voxel " << i << " entry " << n;
      }
      segments += d.segment_count;
    }
    EXPECT_EQ(segments, plan.segments_drawn);
    // The same view again writes the same arrays.
    std::vector<std::vector<std::uint32_t>> before;
    for (std::uint32_t c = 0; c < layout.texture_spans().size(); ++c) before.push_back(sorter.span_order(c));
    sorter.sort(view, plan);
    for (std::uint32_t c = 0; c < layout.texture_spans().size(); ++c) EXPECT_EQ(sorter.span_order(c), before[c]);
  }
}

}  // namespace
}  // namespace vxl
