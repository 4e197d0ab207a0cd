// Reading a .vxl by byte ranges (format/vxl_fetch_plan.h), as the web viewer does over HTTP Range requests: a
// buffer holding only what ranges_to_open and ranges_of_level name (the rest filled with garbage) opens, passes
// the draw checks and draws that level exactly as the whole file does; a level whose spans come one at a time, the
// nearest the view first, draws those in with a coarser level in place of the others.
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <thread>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/vxl_fetch_plan.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"

namespace vxl {
namespace {

using test::gl_context;
using test::render_image;
using test::ScratchDir;

// The file's bytes where `held` says, 0xA5 elsewhere, as a reader's buffer of the file's size.
MappedFile partial_copy(const std::vector<std::uint8_t>& whole, std::span<const ByteRange> held) {
  auto* buffer = static_cast<std::uint8_t*>(std::malloc(whole.size()));
  std::memset(buffer, 0xA5, whole.size());
  for (const ByteRange& r : held) std::memcpy(buffer + r.begin, whole.data() + r.begin, r.end - r.begin);
  return MappedFile::adopt("partial.vxl", buffer, whole.size());
}

// A synthetic scene with levels of detail, packed positions or float32 (the parameter): dir/scene.vxl, whole() its
// bytes and first() the first of them a reader fetches.
class FetchByRanges : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    gl_context();
    SynthSettings synth;
    synth.streamlines = 12000;
    ConvertSettings s;
    s.voxel_size = 10;
    s.levels = 4;
    s.positions = GetParam() ? PositionEncoding::Packed : PositionEncoding::Float32;
    convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
    whole = test::slurp<std::vector<std::uint8_t>>(dir.file("scene.vxl"));
    first = std::span<const std::uint8_t>(whole.data(), std::min<std::size_t>(whole.size(), kSectionTableBytesMax));
  }
  ScratchDir dir;
  std::vector<std::uint8_t> whole;
  std::span<const std::uint8_t> first;
};

TEST_P(FetchByRanges, ALevelDrawsFromItsRangesAloneAsFromTheWholeFile) {
  const std::vector<ByteRange> to_open = ranges_to_open("scene.vxl", first, whole.size());
  const VxlFile reference = VxlFile::open(dir.file("scene.vxl"));
  RenderSettings settings;
  settings.opacity = 0.3f;
  for (const std::uint32_t level : {1u, 2u, 3u}) {
    std::vector<ByteRange> held = to_open;
    const std::vector<ByteRange> of_level = ranges_of_level(reference, level, 0);
    held.insert(held.end(), of_level.begin(), of_level.end());
    held = merge_ranges(held, 0);
    std::uint64_t bytes = 0;
    for (const ByteRange& r : held) bytes += r.end - r.begin;
    EXPECT_LT(bytes, whole.size() / 4) << "level " << level << ": a small part of the file";

    const VxlFile partial = VxlFile::open(partial_copy(whole, held));
    Renderer from_ranges(partial, 0, level), from_whole(reference, 0, level);
    const Image a = render_image(from_ranges, test::synth_brain_view(), settings, 96, 96);
    from_ranges.check_uploaded(true);  // throws on a damaged block or order
    const Image b = render_image(from_whole, test::synth_brain_view(), settings, 96, 96);
    EXPECT_GT(test::lit_pixels(b), 200);
    EXPECT_EQ(a.rgba, b.rgba) << "level " << level;
  }
}

// The picture `r` draws in pieces with `stand_in` for its voxels whose span is not resident.
Image mixed_picture(Renderer& r, Renderer* stand_in, const Camera& camera, const RenderSettings& settings, int size) {
  OffscreenTarget target(size, size);
  r.begin_pieces(camera, settings, size, size, target.framebuffer(), stand_in);
  int pieces = 0;
  while (!r.draw_piece(5) && ++pieces < 100000) {
  }
  glFinish();
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  return Image{size, size, target.read_rgba()};
}

TEST_P(FetchByRanges, TheSpansInAreDrawnWithACoarserLevelInPlaceOfTheRest) {
  const VxlFile reference = VxlFile::open(dir.file("scene.vxl"));
  const std::vector<const VxlFile*> whole_file{&reference};
  const std::uint64_t small_spans = 2 * SceneLayout::largest_voxel_texels(whole_file);
  const Camera camera = test::synth_brain_view();
  RenderSettings settings;
  settings.opacity = 0.3f;
  constexpr int kSize = 96;
  constexpr std::uint32_t kCoarse = 2;

  // The view's spans, nearest first; the nearer half of them fetched, with the coarse level and what opens the file.
  Renderer probe(whole_file, small_spans, 0, nullptr, false);
  const std::vector<std::uint32_t> nearest_first = probe.spans_for(camera, 1.0);
  ASSERT_GE(nearest_first.size(), 4u);
  const std::set<std::uint32_t> in(nearest_first.begin(), nearest_first.begin() + nearest_first.size() / 2);
  std::vector<ByteRange> held = ranges_to_open("scene.vxl", first, whole.size());
  for (const ByteRange& r : ranges_of_level(reference, kCoarse, 0)) held.push_back(r);
  for (const std::uint32_t span : in) {
    const TextureSpan& c = probe.layout().texture_spans()[span];
    for (const ByteRange& r : ranges_of_voxels(reference, 0, c.voxel_first, c.voxel_count, 0)) held.push_back(r);
  }
  const VxlFile partial = VxlFile::open(partial_copy(whole, merge_ranges(held, 0)));
  const std::vector<const VxlFile*> partial_file{&partial};
  Renderer fine(partial_file, small_spans, 0, nullptr, false), coarse(partial_file, 0, kCoarse);
  const auto fetched = [&](std::uint32_t span) { return in.count(span) > 0; };
  std::vector<std::uint32_t> view_spans_in;
  for (const std::uint32_t span : fine.spans_for(camera, 1.0))
    if (fetched(span)) view_spans_in.push_back(span);
  while (!fine.upload_spans(view_spans_in, std::numeric_limits<double>::infinity())) {
  }
  for (std::uint32_t span = 0; span < fine.layout().texture_spans().size(); ++span)
    EXPECT_EQ(fine.span_resident(span), fetched(span)) << "span " << span;
  fine.check_uploaded(true);  // the spans fetched pass the draw checks: their ranges are all they read
  const Image mixed = mixed_picture(fine, &coarse, camera, settings, kSize);
  EXPECT_GT(fine.stats().voxels_drawn, 0u);
  EXPECT_GT(fine.stats().voxels_waiting, 0u) << "drawn from the coarse level";

  // With none of its spans the picture is the coarse level's, with all of them full detail's: the same bytes.
  Renderer coarse_whole(reference, 0, kCoarse), none_in(whole_file, small_spans, 0, nullptr, false),
      all_in(whole_file, small_spans, 0);
  const Image coarse_picture = render_image(coarse_whole, camera, settings, kSize, kSize);
  const Image full_picture = render_image(all_in, camera, settings, kSize, kSize);
  EXPECT_EQ(
      compare_images(mixed_picture(none_in, &coarse_whole, camera, settings, kSize), coarse_picture).differing_pixels,
      0u);
  EXPECT_EQ(none_in.gpu_bytes(), 0u) << "a stand-in's frame uploads nothing";
  EXPECT_EQ(
      compare_images(mixed_picture(all_in, &coarse_whole, camera, settings, kSize), full_picture).differing_pixels, 0u);
  // The half: some pixels as neither.
  EXPECT_GT(compare_images(mixed, coarse_picture).differing_pixels, 0u);
  EXPECT_GT(compare_images(mixed, full_picture).differing_pixels, 0u);
}

INSTANTIATE_TEST_SUITE_P(Positions, FetchByRanges, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "Packed" : "Float32"; });

TEST(FetchPlan, RangesMergeAndTheMissingOnesCoverTheRest) {
  EXPECT_EQ(merge_ranges({{10, 20}, {0, 5}, {18, 30}, {34, 40}, {7, 7}}, 0),
            (std::vector<ByteRange>{{0, 5}, {10, 30}, {34, 40}}));
  EXPECT_EQ(merge_ranges({{10, 20}, {0, 5}, {34, 40}}, 5), (std::vector<ByteRange>{{0, 20}, {34, 40}}));
  const std::vector<ByteRange> held{{0, 5}, {10, 30}, {34, 40}};
  EXPECT_EQ(ranges_missing(held, 50), (std::vector<ByteRange>{{5, 10}, {30, 34}, {40, 50}}));
  EXPECT_EQ(ranges_missing(held, 40), (std::vector<ByteRange>{{5, 10}, {30, 34}}));
  EXPECT_EQ(ranges_missing({}, 3), (std::vector<ByteRange>{{0, 3}}));
  EXPECT_EQ(ranges_missing(std::vector<ByteRange>{{0, 5}, {8, 12}}, 6), (std::vector<ByteRange>{{5, 6}}))
      << "held past the end";
  EXPECT_EQ(ranges_intersection(held, std::vector<ByteRange>{{3, 12}, {20, 36}, {39, 60}}),
            (std::vector<ByteRange>{{3, 5}, {10, 12}, {20, 30}, {34, 36}, {39, 40}}));
  EXPECT_TRUE(ranges_intersection(held, {}).empty());
  EXPECT_TRUE(ranges_held(std::vector<ByteRange>{{0, 5}, {12, 30}, {34, 34}, {36, 40}}, held));
  EXPECT_FALSE(ranges_held(std::vector<ByteRange>{{0, 6}}, held));
  EXPECT_FALSE(ranges_held(std::vector<ByteRange>{{28, 35}}, held)) << "across a gap";
  EXPECT_FALSE(ranges_held(std::vector<ByteRange>{{40, 41}}, held)) << "past the last";
  EXPECT_FALSE(ranges_held(std::vector<ByteRange>{{5, 9}}, held)) << "in a gap";
  EXPECT_TRUE(ranges_held({}, held));
  EXPECT_EQ(ranges_prefix(held, 12), (std::vector<ByteRange>{{0, 5}, {10, 17}})) << "cut inside a range";
  EXPECT_EQ(ranges_prefix(held, 31), held) << "exactly the ranges' 31 bytes";
  EXPECT_EQ(ranges_prefix(held, 1000), held);
  EXPECT_TRUE(ranges_prefix(held, 0).empty());
}

// read_ahead_level asks the system for a level's bytes: evicted from the page cache, they are back in it shortly after,
// without this process reading one of them (mincore: the page cache's view of the file).
TEST(FetchPlan, ALevelReadAheadBringsItsBytesIntoThePageCache) {
  ScratchDir dir;
  SynthSettings synth;
  synth.streamlines = 20000;
  ConvertSettings s;
  s.levels = 4;
  convert_tractogram(synthesize_tractogram(synth), dir.file("scene.vxl"), s);
  const VxlFile file = VxlFile::open(dir.file("scene.vxl"));
  const std::vector<ByteRange> level = ranges_of_level(file, 1, 0);
  const long page = ::sysconf(_SC_PAGESIZE);
  auto pages_out = [&] {  // the level's pages not in the page cache
    std::uint64_t out = 0;
    for (const ByteRange& r : level) {
      const std::uint64_t first = r.begin / page * page;
      std::vector<unsigned char> in((r.end - first + page - 1) / page);
      EXPECT_EQ(::mincore(const_cast<std::uint8_t*>(file.bytes().data()) + first, r.end - first, in.data()), 0);
      for (unsigned char c : in) out += (c & 1) == 0;
    }
    return out;
  };
  {
    const int fd = ::open(dir.file("scene.vxl").c_str(), O_RDONLY);
    ASSERT_GE(fd, 0);
    ::fdatasync(fd);
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
  }
  if (pages_out() == 0) GTEST_SKIP() << "this file system keeps the file in memory: nothing to read ahead";
  read_ahead_level(file, 1);
  std::uint64_t out = pages_out();
  for (int wait = 0; wait < 100 && out > 0; ++wait) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    out = pages_out();
  }
  EXPECT_EQ(out, 0u) << "pages of level 1 still not read after 5 s";
}

TEST(FetchPlan, TheFirstBytesAreCheckedAsOpenChecksThem) {
  ScratchDir dir;
  SynthSettings synth;
  synth.streamlines = 500;
  convert_tractogram(synthesize_tractogram(synth), dir.file("small.vxl"), ConvertSettings{});
  const std::vector<std::uint8_t> whole = test::slurp<std::vector<std::uint8_t>>(dir.file("small.vxl"));
  const auto expect_refused = [](std::span<const std::uint8_t> first, std::uint64_t size, const std::string& what) {
    try {
      ranges_to_open("small.vxl", first, size);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_refused(std::span(whole).first(80), whole.size(), "end before the section table");
  expect_refused(std::span(whole).first(4096), whole.size() - 1, "truncated or extended");
  const std::string tck = "mrtrix tracks\nfile: . 40\nEND\n";
  expect_refused(std::span(reinterpret_cast<const std::uint8_t*>(tck.data()), tck.size()), 4096, "MRtrix TCK");
  // Every section open() needs lies in the ranges; the point and order data do not.
  const std::vector<ByteRange> ranges = ranges_to_open("small.vxl", std::span(whole).first(4096), whole.size());
  const VxlFile f = VxlFile::open(dir.file("small.vxl"));
  const auto held = [&](std::uint64_t at) {
    for (const ByteRange& r : ranges)
      if (at >= r.begin && at < r.end) return true;
    return false;
  };
  for (const std::uint32_t id : {section_id("META"), section_id("DIRS"), section_id("VOXT"), section_id("LODS")})
    EXPECT_TRUE(held(f.find_section(id)->offset)) << section_name(id);
  EXPECT_FALSE(held(f.find_section(section_id("VERT"))->offset));
  EXPECT_FALSE(held(f.orders_offset()));
}

}  // namespace
}  // namespace vxl
