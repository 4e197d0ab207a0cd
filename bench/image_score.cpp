// Scores images against a reference with the trade study's metrics (viewer/platform/image_metrics.h): RMSE,
// PSNR, mean and max absolute error in 8-bit levels over R, G, B, and SSIM. Prints one line per image.
//
// Usage: image_score REFERENCE.png IMAGE.png [IMAGE.png ...]
#include <cstdio>
#include <exception>

#include "viewer/platform/image_io.h"
#include "viewer/platform/image_metrics.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: image_score REFERENCE.png IMAGE.png [IMAGE.png ...]\n");
    return 2;
  }
  try {
    const vxl::Image reference = vxl::read_image(argv[1]);
    for (int i = 2; i < argc; ++i) {
      const vxl::ImageScore s = vxl::score_image(vxl::read_image(argv[i]), reference);
      std::printf("%s vs %s: RMSE %.3f  PSNR %.2f dB  mean abs %.3f  max abs %.0f  SSIM %.5f\n", argv[i], argv[1],
                  s.rmse, s.psnr, s.mean_abs, s.max_abs, s.ssim);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "image_score: %s\n", e.what());
    return 1;
  }
  return 0;
}
