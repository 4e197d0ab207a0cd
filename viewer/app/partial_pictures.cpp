#include "viewer/app/partial_pictures.h"

#include <algorithm>

namespace vxl::app {

void PartialPictureRule::picture_shown(std::uint64_t spans_in) {
  upload_ms_ = 0;
  shown_ = spans_in;
}

bool PartialPictureRule::wants_picture(std::uint64_t spans_in, double picture_ms) const {
  if (!spans_arrived(spans_in)) return false;
  return choice_ == PartialPictures::Always || upload_ms_ >= picture_ms;
}

double partial_picture_ms(std::uint64_t segments_in, std::uint64_t segments_all, std::uint64_t stand_in_segments,
                          double segments_per_ms) {
  const double share_in = segments_all > 0 ? double(std::min(segments_in, segments_all)) / double(segments_all) : 1.0;
  return (double(segments_in) + (1.0 - share_in) * double(stand_in_segments)) / std::max(segments_per_ms, 1e-9);
}

}  // namespace vxl::app
