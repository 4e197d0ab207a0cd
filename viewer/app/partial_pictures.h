// What the window shows at rest while the level it refines to is still being uploaded. The refinement uploads that
// level's spans a few a frame, those of the nearest voxels first, so that its event loop never waits on an upload;
// meanwhile the picture on screen (a coarser level) stays. A partial picture draws the spans in so far with the level
// on screen standing in for the others (Renderer::begin_pieces' stand-in): the detail arrives near the camera first.
// Each partial picture delays the level's complete one by the time it takes to draw, so `auto` draws one only once
// the upload has gone on, since the last picture was shown, at least as long as that picture took to draw: partial
// pictures then take at most half of the wait. Where drawing a level takes far longer than uploading it (a software
// renderer) that is never; on a GPU with a large level, a few. Pure logic, testable without GL.
#pragma once

#include <cstdint>

namespace vxl::app {

enum class PartialPictures {
  Auto,    // when the upload has run longer than the last picture took to draw
  Always,  // whenever spans arrived since the last picture (each picture delays the complete one)
  Never,   // the picture on screen stays until the level is complete
};

class PartialPictureRule {
 public:
  explicit PartialPictureRule(PartialPictures choice = PartialPictures::Auto) : choice_(choice) {}

  // A picture was shown: drawn whole, or the last of its pieces drawn. draw_ms: drawing it took this long (all its
  // pieces); partial_bytes: for a partial picture, the uploading level's bytes it drew from (else 0).
  void picture_shown(double draw_ms, std::uint64_t partial_bytes = 0);
  // The refinement spent `ms` uploading the level's spans.
  void uploaded(double ms) { upload_ms_ += ms; }
  // Whether to draw a partial picture now, the uploading level having `resident_bytes` on the GPU.
  bool wants_picture(std::uint64_t resident_bytes) const;

 private:
  PartialPictures choice_;
  double draw_ms_ = 0;             // the last picture shown took this long to draw
  double upload_ms_ = 0;           // uploading since it was shown
  std::uint64_t shown_bytes_ = 0;  // the uploading level's bytes it drew from
};

}  // namespace vxl::app
