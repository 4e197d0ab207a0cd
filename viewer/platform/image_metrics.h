#pragma once
// How far a rendered image is from a reference: the numbers the speed/accuracy study reports.
//
//   ImageScore s = score_image(rendered, exact);   // RMSE, PSNR, mean/max abs error, SSIM
//
// Errors are taken over the colour channels only: every mode renders over an opaque background, so alpha
// is 255 everywhere and would only dilute the averages. Error values are in 8-bit levels (0..255).

#include "viewer/platform/image_io.h"

namespace vxl {

struct ImageScore {
  double rmse = 0;      // root mean square error over R, G, B, in levels
  double psnr = 0;      // 20 log10(255 / rmse) dB; +inf when the images are equal
  double mean_abs = 0;  // mean absolute error over R, G, B, in levels
  double max_abs = 0;   // largest absolute channel difference, in levels
  double ssim = 1;      // mean SSIM of the luminance (ssim_luminance); 1 when the images are equal
};

// RMSE, PSNR, mean and max error through OpenImageIO's ImageBufAlgo::compare (restricted to R, G, B), and
// SSIM. Throws std::runtime_error when the sizes differ or an image is smaller than 11 x 11.
ImageScore score_image(const Image& test, const Image& reference);

// Mean absolute difference over R, G, B in levels (OpenImageIO's compare): the flicker measure between
// two consecutive frames. Throws std::runtime_error when the sizes differ.
double mean_abs_difference(const Image& a, const Image& b);

// How much an image's deviation from its reference changes from one frame to the next: the mean over R, G,
// B of |(b - b_ref) - (a - a_ref)|, in levels. 0 when both frames equal their references, or keep the same
// error; it isolates flicker that the reference does not have (such as stored orders switching while the
// view turns). Throws std::runtime_error when the sizes differ.
double error_change(const Image& a, const Image& a_ref, const Image& b, const Image& b_ref);

// The structural similarity index of Wang, Bovik, Sheikh & Simoncelli ("Image quality assessment: from
// error visibility to structural similarity", IEEE TIP 2004), as their reference implementation computes
// it for 8-bit images: on the luminance Y = 0.299 R + 0.587 G + 0.114 B (0..255), local statistics under
// an 11 x 11 Gaussian window (sigma 1.5) at every position where the window fits inside the image,
// C1 = (0.01 * 255)^2, C2 = (0.03 * 255)^2, averaged over those positions. 1 for equal images, less
// otherwise (it can be negative). Throws std::runtime_error when the sizes differ or an image is smaller
// than the window.
double ssim_luminance(const Image& a, const Image& b);

}  // namespace vxl
