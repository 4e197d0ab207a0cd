#include "viewer/platform/image_metrics.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "viewer/platform/picture_module_loader.h"

namespace vxl {

namespace {

void check_same_size(const Image& a, const Image& b, const char* who) {
  const std::size_t pixels = static_cast<std::size_t>(a.width) * static_cast<std::size_t>(a.height);
  if (a.width != b.width || a.height != b.height || a.width <= 0 || a.height <= 0 || a.rgba.size() != pixels * 4 ||
      b.rgba.size() != pixels * 4)
    throw std::runtime_error(std::string(who) + ": images must be equal-sized, well-formed RGBA8 (" +
                             std::to_string(a.width) + "x" + std::to_string(a.height) + " vs " +
                             std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
}

// ImageBufAlgo::compare over the colour channels, values on OpenImageIO's 0..1 scale.
pictures::Comparison compare_rgb(const Image& a, const Image& b) {
  pictures::Comparison r;
  std::string error;
  // Thresholds 1: nothing counts as a failure, so a false return means the comparison itself failed.
  if (!pictures::picture_module("").compare(a.width, a.height, a.rgba.data(), b.rgba.data(), 3, 1.0f, 1.0f, r, error))
    throw std::runtime_error("image comparison failed: " + error);
  return r;
}

constexpr int kWindow = 11;  // SSIM window side (Wang et al. 2004)
constexpr double kSigma = 1.5;

std::vector<double> luminance(const Image& img) {
  std::vector<double> y(static_cast<std::size_t>(img.width) * img.height);
  for (std::size_t i = 0; i < y.size(); ++i) {
    const std::uint8_t* p = img.rgba.data() + 4 * i;
    y[i] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
  }
  return y;
}

}  // namespace

double mean_abs_difference(const Image& a, const Image& b) {
  check_same_size(a, b, "mean_abs_difference");
  return compare_rgb(a, b).mean_error * 255.0;
}

double error_change(const Image& a, const Image& a_ref, const Image& b, const Image& b_ref) {
  check_same_size(a, a_ref, "error_change");
  check_same_size(a, b, "error_change");
  check_same_size(a, b_ref, "error_change");
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < a.rgba.size(); ++i) {
    if (i % 4 == 3) continue;  // alpha
    const int change = (int(b.rgba[i]) - int(b_ref.rgba[i])) - (int(a.rgba[i]) - int(a_ref.rgba[i]));
    sum += static_cast<std::uint64_t>(change < 0 ? -change : change);
  }
  return double(sum) / (double(a.rgba.size()) / 4 * 3);
}

// OpenImageIO 2.4 has no SSIM (ImageBufAlgo offers compare, i.e. mean/RMS/PSNR/max, and Yee's perceptual
// pass/fail count), so it is computed here, as Wang et al.'s reference code does.
double ssim_luminance(const Image& a, const Image& b) {
  check_same_size(a, b, "ssim_luminance");
  if (a.width < kWindow || a.height < kWindow)
    throw std::runtime_error("ssim_luminance: images smaller than the 11 x 11 window");
  const int w = a.width, h = a.height, ow = w - kWindow + 1, oh = h - kWindow + 1;

  double g[kWindow], sum = 0;
  for (int i = 0; i < kWindow; ++i) sum += g[i] = std::exp(-0.5 * std::pow((i - kWindow / 2) / kSigma, 2.0));
  for (double& v : g) v /= sum;

  // The five local moments (x, y, x², y², xy), filtered by the separable window: rows first ("valid"
  // positions only), then columns.
  const std::vector<double> x = luminance(a), y = luminance(b);
  constexpr int kMoments = 5;
  std::vector<double> rows(static_cast<std::size_t>(kMoments) * ow * h);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < ow; ++c) {
      double m[kMoments] = {};
      for (int k = 0; k < kWindow; ++k) {
        const std::size_t i = static_cast<std::size_t>(r) * w + c + k;
        m[0] += g[k] * x[i];
        m[1] += g[k] * y[i];
        m[2] += g[k] * x[i] * x[i];
        m[3] += g[k] * y[i] * y[i];
        m[4] += g[k] * x[i] * y[i];
      }
      for (int q = 0; q < kMoments; ++q) rows[(static_cast<std::size_t>(q) * h + r) * ow + c] = m[q];
    }

  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double total = 0;
  for (int r = 0; r < oh; ++r)
    for (int c = 0; c < ow; ++c) {
      double m[kMoments] = {};
      for (int q = 0; q < kMoments; ++q)
        for (int k = 0; k < kWindow; ++k) m[q] += g[k] * rows[(static_cast<std::size_t>(q) * h + r + k) * ow + c];
      const double mx = m[0], my = m[1];
      const double vx = m[2] - mx * mx, vy = m[3] - my * my, cxy = m[4] - mx * my;
      total += ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
  return total / (static_cast<double>(ow) * oh);
}

ImageScore score_image(const Image& test, const Image& reference) {
  check_same_size(test, reference, "score_image");
  const pictures::Comparison r = compare_rgb(test, reference);
  ImageScore s;
  s.rmse = r.rms_error * 255.0;
  s.psnr = r.rms_error > 0 ? 20.0 * std::log10(1.0 / r.rms_error) : std::numeric_limits<double>::infinity();
  s.mean_abs = r.mean_error * 255.0;
  s.max_abs = r.max_error * 255.0;
  s.ssim = ssim_luminance(test, reference);
  return s;
}

}  // namespace vxl
