// The GPU memory budget (gpu_memory_pool.h, GpuScene::make_resident): never exceeded, the nearest visible
// spans first, the least recently used evicted, and an evicted span draws the same picture once uploaded
// again.
#include <chrono>
#include <memory>

#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"
#include "viewer/render/gl_util.h"
#include "viewer/render/gpu_memory_pool.h"
#include "viewer/render/upload_tally.h"
#include "viewer/render/view_queries.h"

namespace vxl {
namespace {

using test::gl_context;
using test::lit_pixels;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

TEST(GpuMemoryPool, EvictsTheLeastRecentlyUsedThatTheCurrentUseDoesNotNeed) {
  GpuMemoryPool pool(100);
  std::vector<std::uint32_t> evicted;
  const std::uint32_t a = pool.add_owner([&](std::uint32_t piece) { evicted.push_back(piece); });
  std::uint64_t use = pool.begin_use();
  for (std::uint32_t piece = 0; piece < 4; ++piece) {
    ASSERT_TRUE(pool.reserve(25, use));
    pool.add(a, piece, 25, use);
  }
  EXPECT_EQ(pool.used(), 100u);
  EXPECT_FALSE(pool.reserve(1, use)) << "every piece is in use";
  EXPECT_TRUE(evicted.empty()) << "a refused reservation evicts nothing";
  use = pool.begin_use();
  pool.touch(a, 0, use);  // 0 is needed now; 1 is the least recently used of the others
  ASSERT_TRUE(pool.reserve(30, use));
  EXPECT_EQ(evicted, (std::vector<std::uint32_t>{1, 2}));
  pool.add(a, 9, 30, use);
  EXPECT_EQ(pool.used(), 80u);
  EXPECT_EQ(pool.peak(), 100u);
  EXPECT_EQ(pool.evictions(), 2u);
  EXPECT_FALSE(pool.reserve(101, pool.begin_use())) << "larger than the budget";
  pool.remove(a, 9);
  EXPECT_EQ(pool.used(), 50u);
}

TEST(GpuMemoryPool, OwnersShareOneBudget) {
  GpuMemoryPool pool(50);
  std::vector<std::uint32_t> evicted_a, evicted_b;
  const std::uint32_t a = pool.add_owner([&](std::uint32_t p) { evicted_a.push_back(p); });
  const std::uint32_t b = pool.add_owner([&](std::uint32_t p) { evicted_b.push_back(p); });
  std::uint64_t use = pool.begin_use();
  ASSERT_TRUE(pool.reserve(40, use));
  pool.add(a, 7, 40, use);
  use = pool.begin_use();
  ASSERT_TRUE(pool.reserve(40, use));  // b's first piece evicts a's
  pool.add(b, 3, 40, use);
  EXPECT_EQ(evicted_a, (std::vector<std::uint32_t>{7}));
  EXPECT_TRUE(evicted_b.empty());
  EXPECT_LE(pool.peak(), 50u);
  pool.remove_owner(b);
  EXPECT_EQ(pool.used(), 0u);
}

// A scene of many small spans under a budget that holds part of it. The voxel table is sorted by (z, y, x)
// and spans are ranges of it, so a clip plane near the bottom or the top keeps a few spans.
class GpuMemoryBudget : public ::testing::Test {
 protected:
  void SetUp() override {
    gl_context();
    SynthSettings synth;
    synth.streamlines = 2000;
    file_.emplace(make_scene(dir_, synthesize_tractogram(synth), 12.0));
    // Small spans: twice the smallest limit that holds the largest voxel.
    for (kTexels = 1000;; kTexels *= 2) try {
        SceneLayout(*file_, kTexels, 0);
        break;
      } catch (const vxl::Error&) {
      }
    kTexels *= 2;
  }
  std::uint64_t kTexels = 0;
  Camera view() const {
    Camera c;
    c.azimuth_deg = 30;
    c.elevation_deg = 10;
    const MetaSection& m = file_->meta();
    c.frame({m.bounds_min[0], m.bounds_min[1], m.bounds_min[2]}, {m.bounds_max[0], m.bounds_max[1], m.bounds_max[2]},
            1.0);
    return c;
  }
  // Axis mode, only what lies within 30 mm of the bottom (or the top).
  RenderSettings near(bool bottom) const {
    RenderSettings s;
    s.opacity = 0.3f;
    AxisClip p;
    p.axis = 2;
    p.keep_above = !bottom;
    p.position = bottom ? file_->meta().bounds_min[2] + 30 : file_->meta().bounds_max[2] - 30;
    s.clipping.planes.push_back(p);
    return s;
  }
  std::uint64_t whole_bytes() const { return SceneLayout(*file_, kTexels, 0).upload_bytes(); }
  // A budget for the spans the bottom's view needs or the top's, not both.
  std::uint64_t bottom_or_top_budget() const {
    Renderer probe({&*file_}, kTexels, 0, std::make_shared<GpuMemoryPool>(0));
    render_image(probe, view(), near(true), 96, 96);
    FramePlan bottom_plan, top_plan;
    probe.plan(view(), 1.0, PlanOrder::Nearest, bottom_plan, near(true).clipping);
    probe.plan(view(), 1.0, PlanOrder::Nearest, top_plan, near(false).clipping);
    auto bytes_of = [&](const FramePlan& p) {
      std::vector<bool> seen(probe.layout().texture_spans().size(), false);
      std::uint64_t bytes = 0;
      for (std::int64_t id : p.first) {
        const std::uint32_t c = probe.layout().span_of_id(id);
        if (seen[c]) continue;
        seen[c] = true;
        const TextureSpan& t = probe.layout().texture_spans()[c];
        bytes += 4 * t.words() + 4 * t.order_words;
      }
      return bytes;
    };
    return std::max(bytes_of(bottom_plan), bytes_of(top_plan));
  }
  ScratchDir dir_;
  std::optional<VxlFile> file_;
};

TEST_F(GpuMemoryBudget, TheBudgetIsNeverExceededAndTheNearestSpansComeFirst) {
  const auto pool = std::make_shared<GpuMemoryPool>(whole_bytes() / 3);
  Renderer r({&*file_}, kTexels, 0, pool);
  ASSERT_GT(r.layout().texture_spans().size(), 8u);
  EXPECT_LE(r.gpu_bytes(), pool->budget()) << "made within the budget";
  RenderSettings whole;
  whole.opacity = 0.3f;
  const Image img = render_image(r, view(), whole, 96, 96);
  EXPECT_GT(lit_pixels(img), 300);
  EXPECT_GT(r.stats().voxels_waiting, 0u) << "a third of the scene's spans cannot hold every visible voxel";
  EXPECT_GT(r.stats().voxels_drawn, 0u);
  // The spans were uploaded nearest voxel first (the plan is back to front), each that still fit.
  FramePlan plan;
  r.plan(view(), 1.0, PlanOrder::Nearest, plan);
  ASSERT_FALSE(plan.first.empty());
  EXPECT_TRUE(r.span_resident(r.layout().span_of_id(plan.first.back())));
  std::vector<bool> seen(r.layout().texture_spans().size(), false);
  std::uint64_t used = 0;
  int waiting = 0;
  for (std::size_t i = plan.first.size(); i-- > 0;) {
    const std::uint32_t c = r.layout().span_of_id(plan.first[i]);
    if (seen[c]) continue;
    seen[c] = true;
    const TextureSpan& t = r.layout().texture_spans()[c];
    const std::uint64_t bytes = 4 * t.words() + 4 * t.order_words;
    const bool fits = used + bytes <= pool->budget();
    if (fits) used += bytes;
    waiting += fits ? 0 : 1;
    EXPECT_EQ(r.span_resident(c), fits) << "span " << c;
  }
  EXPECT_GT(waiting, 0);
  for (bool bottom : {true, false, true}) render_image(r, view(), near(bottom), 96, 96);
  EXPECT_LE(pool->peak(), pool->budget());
  EXPECT_LE(r.gpu_bytes(), pool->budget());
  EXPECT_EQ(r.gpu_bytes(), pool->used());
}

TEST_F(GpuMemoryBudget, AViewsBytesAreKnownFromTheLayoutAlone) {
  // view_queries.h works on the layout, before any renderer exists (the viewer's level choice).
  const SceneLayout layout(*file_, kTexels, 0);
  const VxlFile* const files[] = {&*file_};
  const SceneBounds bounds = line_bounds(files);
  const std::uint64_t whole = view_bytes(layout, view(), 1.0, bounds, {});
  const std::uint64_t bottom = view_bytes(layout, view(), 1.0, bounds, near(true).clipping);
  EXPECT_GT(bottom, 0u);
  EXPECT_LT(bottom, whole) << "a slab near the bottom needs fewer spans than the whole view";
  EXPECT_LE(whole, layout.upload_bytes());
  Renderer r({&*file_}, kTexels, 0, std::make_shared<GpuMemoryPool>(0), false);
  EXPECT_EQ(r.view_bytes(view(), 1.0, near(true).clipping), bottom) << "the renderer answers the same";
  EXPECT_EQ(r.view_bytes(view(), 1.0), whole);
}

TEST_F(GpuMemoryBudget, EvictedSpansDrawTheSamePictureWhenUploadedAgain) {
  const auto unlimited = std::make_shared<GpuMemoryPool>();
  Renderer reference({&*file_}, kTexels, 0, unlimited);
  const Image bottom_reference = render_image(reference, view(), near(true), 96, 96);
  ASSERT_GT(lit_pixels(bottom_reference), 100);

  const std::uint64_t budget = bottom_or_top_budget();
  ASSERT_LT(budget, whole_bytes()) << "the test needs views that do not take the whole scene";

  const auto pool = std::make_shared<GpuMemoryPool>(budget);
  Renderer r({&*file_}, kTexels, 0, pool);
  const Image first = render_image(r, view(), near(true), 96, 96);
  EXPECT_EQ(r.stats().voxels_waiting, 0u);
  const std::uint64_t evictions = pool->evictions(), additions = pool->additions();
  const Image top = render_image(r, view(), near(false), 96, 96);
  EXPECT_EQ(r.stats().voxels_waiting, 0u);
  EXPECT_GT(pool->evictions(), evictions) << "the top's spans made room by evicting the bottom's";
  const Image again = render_image(r, view(), near(true), 96, 96);
  EXPECT_GT(pool->additions(), additions + 1) << "the bottom's spans were uploaded again";
  EXPECT_EQ(compare_images(first, again).differing_pixels, 0u);
  EXPECT_EQ(compare_images(first, bottom_reference).differing_pixels, 0u) << "and it is the unbudgeted picture";
  EXPECT_LE(pool->peak(), budget);
  EXPECT_GT(lit_pixels(top), 100);
}

// On llvmpipe a span's buffers are host memory handed to the driver (gl::host_memory_buffers), which the driver
// neither clears nor copies. They draw what the driver's own buffers draw, also when spans are evicted (their
// memory given back once the driver is done with it) and uploaded again.
TEST_F(GpuMemoryBudget, HostMemoryBuffersDrawWhatTheDriversOwnDraw) {
  const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  if (renderer.find("llvmpipe") == std::string::npos)
    GTEST_SKIP() << "host memory buffers are for Mesa's llvmpipe; this context is " << renderer;
  ASSERT_TRUE(epoxy_has_gl_extension("GL_AMD_pinned_memory")) << "Mesa's llvmpipe offers to take host memory";
  const std::uint64_t budget = bottom_or_top_budget();
  struct Pictures {
    Image bottom, top, bottom_again;
    std::uint64_t evictions = 0;
    bool host_memory = false;
  };
  // The choice is the process's: restored however a draw ends.
  struct BufferMemoryChoice {
    explicit BufferMemoryChoice(gl::BufferMemory memory) { gl::set_buffer_memory(memory); }
    ~BufferMemoryChoice() { gl::set_buffer_memory(gl::BufferMemory::Auto); }
  };
  auto draw = [&](gl::BufferMemory memory) {
    const BufferMemoryChoice choice(memory);
    const auto pool = std::make_shared<GpuMemoryPool>(budget);
    Pictures p;
    p.host_memory = gl::host_memory_buffers();
    {
      Renderer r({&*file_}, kTexels, 0, pool);
      p.bottom = render_image(r, view(), near(true), 96, 96);
      p.top = render_image(r, view(), near(false), 96, 96);
      p.bottom_again = render_image(r, view(), near(true), 96, 96);
      r.check_uploaded(true);
    }
    p.evictions = pool->evictions();
    return p;
  };
  const Pictures host = draw(gl::BufferMemory::Auto), driver = draw(gl::BufferMemory::Driver);
  EXPECT_TRUE(host.host_memory);
  EXPECT_FALSE(driver.host_memory);
  EXPECT_GT(host.evictions, 0u) << "the top's spans made room by evicting the bottom's";
  EXPECT_EQ(host.evictions, driver.evictions);
  EXPECT_GT(lit_pixels(host.bottom), 100);
  EXPECT_GT(lit_pixels(host.top), 100);
  EXPECT_EQ(compare_images(host.bottom, driver.bottom).differing_pixels, 0u);
  EXPECT_EQ(compare_images(host.top, driver.top).differing_pixels, 0u);
  EXPECT_EQ(compare_images(host.bottom_again, driver.bottom_again).differing_pixels, 0u);
}

// A window spreads a large upload over frames: upload_spans fills a few spans at a time on other threads, the
// nearest first, returns after about its time limit with those done resident, and says when the view has all
// it needs; the picture is then the eager scene's.
TEST_F(GpuMemoryBudget, UploadsSpreadOverCallsGiveTheSamePicture) {
  Renderer eager({&*file_}, kTexels, 0);
  Renderer lazy({&*file_}, kTexels, 0, std::make_shared<GpuMemoryPool>(), /*eager=*/false);
  EXPECT_GT(eager.gpu_bytes(), 0u);
  EXPECT_EQ(lazy.gpu_bytes(), 0u) << "nothing uploaded before a frame needs it";
  RenderSettings s;
  s.opacity = 0.3f;
  int calls = 1;
  std::uint64_t before = 0;
  const std::vector<std::uint32_t> spans = lazy.spans_for(view(), 1.0, s.clipping);
  while (!lazy.upload_spans(spans, 1e-6)) {  // a millionth of a millisecond: hardly any wait
    EXPECT_GE(lazy.gpu_bytes(), before) << "call " << calls;
    before = lazy.gpu_bytes();
    ASSERT_LT(++calls, 1000000) << "the uploads never end";
  }
  EXPECT_GT(calls, 4) << "spread over calls, a few spans filling at a time";
  FramePlan plan;
  lazy.plan(view(), 1.0, PlanOrder::Nearest, plan);
  EXPECT_TRUE(lazy.span_resident(lazy.layout().span_of_id(plan.first.back())));
  const std::uint64_t uploaded = lazy.gpu_bytes();
  const Image a = render_image(eager, view(), s, 96, 96), b = render_image(lazy, view(), s, 96, 96);
  EXPECT_EQ(lazy.gpu_bytes(), uploaded) << "the frame found every span it needed";
  EXPECT_EQ(compare_images(a, b).differing_pixels, 0u);
  // Each pool's tally holds every span it uploaded, however the uploads were spread (nothing was evicted).
  for (const Renderer* r : {&eager, &lazy}) {
    const UploadTally& t = r->gpu_memory().uploads();
    EXPECT_EQ(t.bytes(), r->gpu_bytes());
    EXPECT_EQ(t.spans(), r->layout().texture_spans().size());
    EXPECT_GT(t.seconds(), 0.0);
    EXPECT_DOUBLE_EQ(t.gb_per_s(), double(t.bytes()) / 1e9 / t.seconds());
  }
}

// Two spans fill at once: the time both were filling is counted once, and a fill's wait to be looked at not at all
// (the caller passes when its fill ended).
TEST(UploadTally, TimeDuringWhichFillsOverlapIsCountedOnce) {
  using Clock = UploadTally::Clock;
  const Clock::time_point t0 = Clock::now();
  const auto at = [&](double s) {
    return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  UploadTally t;
  EXPECT_EQ(t.gb_per_s(), 0.0) << "nothing uploaded yet";
  t.add(1'000'000'000, at(0), at(2));
  t.add(1'000'000'000, at(1), at(3));    // overlaps the first by a second
  t.add(500'000'000, at(1.5), at(2.5));  // within both
  EXPECT_NEAR(t.seconds(), 3.0, 1e-9);
  t.add(1'500'000'000, at(5), at(6));  // after an idle second, which does not count
  EXPECT_NEAR(t.seconds(), 4.0, 1e-9);
  EXPECT_EQ(t.bytes(), 4'000'000'000u);
  EXPECT_EQ(t.spans(), 4u);
  EXPECT_NEAR(t.gb_per_s(), 1.0, 1e-9);
  // Fills end in either order: one that began earlier may be added after a later one, and its own time still counts.
  t.add(0, at(8), at(9));
  t.add(0, at(7), at(8.5));  // began before the one added last: 7 to 8 is its alone
  EXPECT_NEAR(t.seconds(), 6.0, 1e-9);
  t.add(0, at(4), at(10));  // spans the gap between the intervals so far and both sides of the last
  EXPECT_NEAR(t.seconds(), 9.0, 1e-9) << "0-3 and 4-10";
  t.add(0, at(2), at(2));  // no time
  EXPECT_NEAR(t.seconds(), 9.0, 1e-9);
  EXPECT_EQ(t.spans(), 8u);
}

// A buffer texture reads zeros past the driver's limit: a buffer larger than it is refused with the sizes named,
// made at once or filled through create_mapped, in the driver's buffers and in host memory (on llvmpipe); one at
// the limit is made.
TEST(GpuBufferLimit, ABufferOverTheDriversLimitIsRefused) {
  gl_context();
  const std::uint64_t limit = gl::max_buffer_texels();
  ASSERT_GT(limit, 0u);
  ASSERT_LE(limit, std::uint64_t(1) << 31) << "one byte a texel below must stay a test-sized buffer";
  gl::TextureBuffer at_limit;
  at_limit.create(GL_R8UI, nullptr, limit);
  EXPECT_NE(at_limit.texture, 0u);
  at_limit.destroy();
  gl::TextureBuffer over;
  try {
    over.create(GL_R8UI, nullptr, limit + 1);
    ADD_FAILURE() << "a buffer of limit + 1 texels was made";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(limit + 1) + " texels"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("GL_MAX_TEXTURE_BUFFER_SIZE"), std::string::npos) << e.what();
  }
  EXPECT_EQ(over.texture, 0u);
  const std::string renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  for (const gl::BufferMemory memory : {gl::BufferMemory::Auto, gl::BufferMemory::Driver}) {
    struct BufferMemoryChoice {  // the process's choice, restored however the loop's body ends
      explicit BufferMemoryChoice(gl::BufferMemory m) { gl::set_buffer_memory(m); }
      ~BufferMemoryChoice() { gl::set_buffer_memory(gl::BufferMemory::Auto); }
    } choice(memory);
    if (renderer.find("llvmpipe") != std::string::npos) {
      EXPECT_EQ(gl::host_memory_buffers(), memory == gl::BufferMemory::Auto) << "both kinds of memory are tried";
    }
    gl::TextureBuffer mapped;
    ASSERT_NE(mapped.create_mapped(limit + 1), nullptr);  // never written
    EXPECT_THROW(mapped.finish_mapped(GL_R8UI), std::runtime_error);
    EXPECT_EQ(mapped.texture, 0u);
    EXPECT_EQ(mapped.buffer, 0u);
    EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  }
}

}  // namespace
}  // namespace vxl
