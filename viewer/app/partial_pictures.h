// What the window shows at rest while the level it refines to is still being uploaded. The refinement uploads that
// level's spans a few a frame, those of the nearest voxels first, so that its event loop never waits on an upload;
// meanwhile the picture on screen (a coarser level) stays. A partial picture draws the view's spans in so far with
// the level on screen standing in for the others (Renderer::begin_pieces' stand-in): the detail arrives near the
// camera first. Each partial picture delays the level's complete one by the time it takes to draw, so `auto` draws one
// only once the upload has gone on, since the last picture was shown, at least as long as the partial picture is
// expected to take (partial_picture_ms): partial pictures then take about half of the wait at most. Where drawing a
// level takes far longer than uploading it (a software renderer) that is never; on a GPU with a large level, a few.
// Pure logic, testable without GL.
#pragma once

#include <cstdint>

namespace vxl::app {

enum class PartialPictures {
  Auto,    // when the upload has run longer than the partial picture would take to draw
  Always,  // whenever spans arrived since the last picture (each picture delays the complete one)
  Never,   // the picture on screen stays until the level is complete
};

class PartialPictureRule {
 public:
  explicit PartialPictureRule(PartialPictures choice = PartialPictures::Auto) : choice_(choice) {}

  // A picture was shown (drawn whole, or the last of its pieces drawn); spans_in: for a partial picture, the view's
  // spans of the uploading level it drew from (else 0).
  void picture_shown(std::uint64_t spans_in = 0);
  // The refinement spent `ms` uploading the level's spans.
  void uploaded(double ms) { upload_ms_ += ms; }
  // Whether the view has more of the uploading level's spans in (`spans_in`) than the picture on screen shows.
  bool spans_arrived(std::uint64_t spans_in) const { return choice_ != PartialPictures::Never && spans_in > shown_; }
  // Whether to draw a partial picture now, with `spans_in` of the view's spans in, expected to take `picture_ms`.
  bool wants_picture(std::uint64_t spans_in, double picture_ms) const;

 private:
  PartialPictures choice_;
  double upload_ms_ = 0;     // uploading since the last picture was shown
  std::uint64_t shown_ = 0;  // the uploading level's spans it drew from
};

// The time a partial picture is expected to take at `segments_per_ms`: the uploading level's segments in
// (`segments_in` of the view's spans' `segments_all`), and the stand-in's picture of the whole view
// (`stand_in_segments`) for the share not in.
double partial_picture_ms(std::uint64_t segments_in, std::uint64_t segments_all, std::uint64_t stand_in_segments,
                          double segments_per_ms);

}  // namespace vxl::app
