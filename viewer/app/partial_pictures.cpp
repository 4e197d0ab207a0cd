#include "viewer/app/partial_pictures.h"

namespace vxl::app {

void PartialPictureRule::picture_shown(double draw_ms, std::uint64_t partial_bytes) {
  draw_ms_ = draw_ms;
  upload_ms_ = 0;
  shown_bytes_ = partial_bytes;
}

bool PartialPictureRule::wants_picture(std::uint64_t resident_bytes) const {
  if (choice_ == PartialPictures::Never || resident_bytes <= shown_bytes_) return false;  // nothing new to show
  return choice_ == PartialPictures::Always || upload_ms_ >= draw_ms_;
}

}  // namespace vxl::app
