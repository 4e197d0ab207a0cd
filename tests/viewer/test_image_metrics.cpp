// The image metrics of the speed/accuracy study: identical images score perfectly, known perturbations
// give the known errors, and SSIM matches a direct (non-separable) evaluation of its definition.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "viewer/platform/image_metrics.h"

namespace vxl {
namespace {

Image filled(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  Image img{w, h, std::vector<std::uint8_t>(std::size_t(w) * h * 4, 255)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      img.pixel(x, y)[0] = r;
      img.pixel(x, y)[1] = g;
      img.pixel(x, y)[2] = b;
    }
  return img;
}

// Deterministic noise in 0..200 (so that +10 never clips).
Image noise(int w, int h, std::uint32_t seed) {
  Image img = filled(w, h, 0, 0, 0);
  for (std::size_t i = 0; i < img.rgba.size(); ++i) {
    seed = seed * 1664525u + 1013904223u;
    if (i % 4 != 3) img.rgba[i] = static_cast<std::uint8_t>((seed >> 24) % 201);
  }
  return img;
}

TEST(ImageMetrics, IdenticalImagesScorePerfectly) {
  Image a = noise(40, 30, 1);
  ImageScore s = score_image(a, a);
  EXPECT_EQ(s.rmse, 0.0);
  EXPECT_EQ(s.mean_abs, 0.0);
  EXPECT_EQ(s.max_abs, 0.0);
  EXPECT_EQ(s.psnr, std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.ssim, 1.0);
  EXPECT_EQ(mean_abs_difference(a, a), 0.0);
}

TEST(ImageMetrics, KnownPerturbationGivesTheKnownErrors) {
  // +10 levels in the red channel of every fourth pixel: of 3 N channel values, N / 4 differ by 10.
  Image a = noise(64, 48, 2), b = a;
  for (int y = 0; y < b.height; ++y)
    for (int x = 0; x < b.width; x += 4) b.pixel(x, y)[0] += 10;
  // Alpha differs too: it must not count (the scores are over R, G, B).
  b.pixel(1, 1)[3] = 0;
  const double rmse = std::sqrt(100.0 / 12.0), mean = 10.0 / 12.0;
  ImageScore s = score_image(b, a);
  EXPECT_NEAR(s.rmse, rmse, 1e-6);
  EXPECT_NEAR(s.mean_abs, mean, 1e-6);
  EXPECT_NEAR(s.max_abs, 10.0, 1e-4);  // OpenImageIO keeps the maximum in float
  EXPECT_NEAR(s.psnr, 20 * std::log10(255.0 / rmse), 1e-6);
  EXPECT_LT(s.ssim, 1.0);
  EXPECT_GT(s.ssim, 0.9);
  EXPECT_NEAR(mean_abs_difference(a, b), mean, 1e-6);
}

TEST(ImageMetrics, SsimOfFlatImagesIsTheLuminanceTerm) {
  // No variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1), the luminance of grey being the grey level.
  const double c1 = (0.01 * 255) * (0.01 * 255);
  const double a = 100, b = 160;
  EXPECT_NEAR(ssim_luminance(filled(20, 20, 100, 100, 100), filled(20, 20, 160, 160, 160)),
              (2 * a * b + c1) / (a * a + b * b + c1), 1e-9);
  // Luminance weights 0.299, 0.587, 0.114: pure red 200 has luminance 59.8, pure blue 200 22.8.
  const double r = 0.299 * 200, bl = 0.114 * 200;
  EXPECT_NEAR(ssim_luminance(filled(12, 12, 200, 0, 0), filled(12, 12, 0, 0, 200)),
              (2 * r * bl + c1) / (r * r + bl * bl + c1), 1e-9);
}

// SSIM straight from its definition: a full 2-D Gaussian window at every valid position.
double direct_ssim(const Image& a, const Image& b) {
  auto lum = [](const Image& img, int x, int y) {
    const std::uint8_t* p = img.pixel(x, y);
    return 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
  };
  double w[11][11], sum = 0;
  for (int i = 0; i < 11; ++i)
    for (int j = 0; j < 11; ++j) sum += w[i][j] = std::exp(-((i - 5) * (i - 5) + (j - 5) * (j - 5)) / (2 * 1.5 * 1.5));
  const double c1 = 6.5025, c2 = 58.5225;
  double total = 0;
  int n = 0;
  for (int y = 0; y + 11 <= a.height; ++y)
    for (int x = 0; x + 11 <= a.width; ++x, ++n) {
      double mx = 0, my = 0, xx = 0, yy = 0, xy = 0;
      for (int i = 0; i < 11; ++i)
        for (int j = 0; j < 11; ++j) {
          const double g = w[i][j] / sum, p = lum(a, x + j, y + i), q = lum(b, x + j, y + i);
          mx += g * p, my += g * q, xx += g * p * p, yy += g * q * q, xy += g * p * q;
        }
      const double vx = xx - mx * mx, vy = yy - my * my, cxy = xy - mx * my;
      total += (2 * mx * my + c1) * (2 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
  return total / n;
}

TEST(ImageMetrics, SsimMatchesItsDefinitionAndIsSymmetric) {
  Image a = noise(23, 17, 3), b = noise(23, 17, 4), c = a;
  for (std::size_t i = 0; i < c.rgba.size(); i += 7) c.rgba[i] = static_cast<std::uint8_t>(c.rgba[i] / 2);
  for (const Image* other : {&b, &c}) {
    EXPECT_NEAR(ssim_luminance(a, *other), direct_ssim(a, *other), 1e-9);
    EXPECT_NEAR(ssim_luminance(a, *other), ssim_luminance(*other, a), 1e-12);
  }
  // Unrelated noise scores far lower than a mild perturbation.
  EXPECT_LT(ssim_luminance(a, b), 0.2);
  EXPECT_GT(ssim_luminance(a, c), 0.5);
}

TEST(ImageMetrics, ErrorChangeCountsOnlyChangesOfTheDeviation) {
  Image ref0 = noise(16, 16, 5), ref1 = noise(16, 16, 6);
  EXPECT_EQ(error_change(ref0, ref0, ref1, ref1), 0.0);  // both frames exact, however different
  // The same error in both frames: no change.
  Image a = ref0, b = ref1;
  a.pixel(3, 3)[1] += 20;
  b.pixel(3, 3)[1] += 20;
  EXPECT_EQ(error_change(a, ref0, b, ref1), 0.0);
  // The error moves to another pixel: two channel values change by 20, of 3 * 256.
  b = ref1;
  b.pixel(4, 3)[1] += 20;
  EXPECT_NEAR(error_change(a, ref0, b, ref1), 40.0 / (3 * 256), 1e-12);
}

TEST(ImageMetrics, MismatchedOrTooSmallImagesAreRefused) {
  EXPECT_THROW(score_image(noise(20, 20, 1), noise(21, 20, 1)), std::runtime_error);
  EXPECT_THROW(ssim_luminance(noise(10, 30, 1), noise(10, 30, 1)), std::runtime_error);
  EXPECT_THROW(mean_abs_difference(noise(5, 5, 1), noise(5, 6, 1)), std::runtime_error);
}

}  // namespace
}  // namespace vxl
