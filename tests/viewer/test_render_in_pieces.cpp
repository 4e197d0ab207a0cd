// A frame drawn in pieces (Renderer::begin_pieces / draw_piece, the window's refinement at rest) gives the
// picture draw() gives, whatever the pieces' size.
#include <stdexcept>
#include <vector>

#include "converter/synth/synth.h"
#include "tests/viewer/render_support.h"
#include "viewer/platform/image_metrics.h"

namespace vxl {
namespace {

using test::gl_context;
using test::lit_pixels;
using test::make_scene;
using test::render_image;
using test::ScratchDir;

class RenderInPieces : public ::testing::Test {
 protected:
  void SetUp() override {
    gl_context();
    SynthSettings synth;
    synth.streamlines = 400;
    file_.emplace(make_scene(dir_, synthesize_tractogram(synth), 12.0));
  }
  static Camera view() {
    Camera c;
    c.azimuth_deg = 35;
    c.elevation_deg = 20;
    c.frame({-70, -105, -50}, {70, 70, 70}, 1.0);
    return c;
  }
  static RenderSettings settings(RenderMode mode) {
    RenderSettings s;
    s.mode = mode;
    s.opacity = 0.3f;
    return s;
  }
  // The picture drawn in pieces of at most `max_ms` each; `pieces` counts them, and every piece's progress
  // must grow.
  Image in_pieces(Renderer& r, const RenderSettings& s, double max_ms, int* pieces) {
    OffscreenTarget target(kSize, kSize);
    r.begin_pieces(view(), s, kSize, kSize, target.framebuffer());
    *pieces = 0;
    double progress = r.pieces_progress();
    bool done = false;
    while (!done && *pieces < 100000) {
      done = r.draw_piece(max_ms);
      ++*pieces;
      EXPECT_GE(r.pieces_progress(), progress) << "piece " << *pieces;
      progress = r.pieces_progress();
    }
    EXPECT_TRUE(done);
    EXPECT_EQ(r.pieces_progress(), 1.0);
    glFinish();
    EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
    return Image{kSize, kSize, target.read_rgba()};
  }
  static constexpr int kSize = 96;
  ScratchDir dir_;
  std::optional<VxlFile> file_;
};

TEST_F(RenderInPieces, SortedModesDrawTheSamePictureASegmentAtATime) {
  Renderer r(*file_);
  for (RenderMode mode : {RenderMode::Axis, RenderMode::Basic, RenderMode::Opaque}) {
    const Image whole = render_image(r, view(), settings(mode), kSize, kSize);
    ASSERT_GT(lit_pixels(whole), 500) << render_mode_name(mode);
    int pieces = 0;
    // A millionth of a millisecond: every piece is one segment, a voxel drawn in many parts.
    const Image pieced = in_pieces(r, settings(mode), 1e-6, &pieces);
    EXPECT_GT(static_cast<std::uint64_t>(pieces), 10 * r.stats().voxels_drawn) << render_mode_name(mode);
    // The same draws in the same order into the same kind of buffer: the same bytes.
    EXPECT_EQ(compare_images(whole, pieced).differing_pixels, 0u) << render_mode_name(mode);
    // Unbounded: one piece.
    EXPECT_EQ(compare_images(whole, in_pieces(r, settings(mode), 1e9, &pieces)).differing_pixels, 0u);
    EXPECT_EQ(pieces, 1) << render_mode_name(mode);
  }
}

TEST_F(RenderInPieces, UnorderedModesAreDrawnWholeByTheFirstPiece) {
  Renderer r(*file_);
  for (RenderMode mode : {RenderMode::Unsorted, RenderMode::Wboit, RenderMode::Additive}) {
    const Image whole = render_image(r, view(), settings(mode), kSize, kSize);
    int pieces = 0;
    const Image pieced = in_pieces(r, settings(mode), 1e-6, &pieces);
    EXPECT_EQ(pieces, 1) << render_mode_name(mode);
    EXPECT_EQ(compare_images(whole, pieced).differing_pixels, 0u) << render_mode_name(mode);
  }
}

TEST_F(RenderInPieces, ExactInShortRunsStaysExact) {
  Renderer r(*file_);
  const Image whole = render_image(r, view(), settings(RenderMode::Exact), kSize, kSize);
  const Image axis = render_image(r, view(), settings(RenderMode::Axis), kSize, kSize);
  int pieces = 0;
  const Image pieced = in_pieces(r, settings(RenderMode::Exact), 1e-6, &pieces);
  EXPECT_GT(pieces, 10) << "a run of one voxel a piece";
  const int lit = lit_pixels(whole);
  ASSERT_GT(lit, 500);
  // As exact in runs of a small node buffer (RenderModes.ExactInDepthPassesEqualsExactInOnePass): equal but
  // where a line ends at a voxel face, its fragments reaching half a pixel into the next run's voxel.
  EXPECT_LE(compare_images(whole, pieced).differing_pixels, std::size_t(lit) / 10);
  EXPECT_LT(score_image(pieced, whole).rmse, 1.0);
  EXPECT_LT(score_image(pieced, whole).rmse, 0.5 * score_image(axis, whole).rmse)
      << "exact in pieces must stay far closer to exact than axis is";
}

TEST_F(RenderInPieces, AWholeFrameAbandonsThePieces) {
  Renderer r(*file_);
  OffscreenTarget target(kSize, kSize);
  r.begin_pieces(view(), settings(RenderMode::Axis), kSize, kSize, target.framebuffer());
  EXPECT_FALSE(r.draw_piece(1e-6));
  r.draw(view(), settings(RenderMode::Axis), kSize, kSize, target.framebuffer());
  EXPECT_EQ(r.pieces_progress(), 0.0);
  EXPECT_THROW(r.draw_piece(1e-6), std::logic_error);
}

}  // namespace
}  // namespace vxl
