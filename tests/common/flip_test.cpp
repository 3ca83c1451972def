// LDR-FLIP on cases whose answers follow from the paper's definitions.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/flip.h"
#include "common/image.h"

namespace canopy {
namespace {

ImageRgba8 uniform(int size, uint8_t r, uint8_t g, uint8_t b) {
  ImageRgba8 image(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      uint8_t* p = image.at(x, y);
      p[0] = r, p[1] = g, p[2] = b, p[3] = 255;
    }
  return image;
}

// A leafy test pattern: random coloured blobs on a mid-grey ground, fixed seed.
ImageRgba8 pattern(int size, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> byte(0, 255), coordinate(0, size - 1), radius(1, 6);
  ImageRgba8 image = uniform(size, 120, 130, 110);
  for (int blob = 0; blob < 60; ++blob) {
    const int cx = coordinate(random), cy = coordinate(random), r = radius(random);
    const uint8_t colour[3] = {uint8_t(byte(random)), uint8_t(byte(random)), uint8_t(byte(random))};
    for (int y = std::max(0, cy - r); y < std::min(size, cy + r + 1); ++y)
      for (int x = std::max(0, cx - r); x < std::min(size, cx + r + 1); ++x)
        if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r)
          for (int c = 0; c < 3; ++c) image.at(x, y)[c] = colour[c];
  }
  return image;
}

// A separable Gaussian blur of the 8-bit values (σ in pixels), borders repeated.
ImageRgba8 blurred(const ImageRgba8& image, double sigma) {
  const int radius = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> weights;
  double sum = 0;
  for (int i = -radius; i <= radius; ++i) {
    weights.push_back(std::exp(-i * i / (2 * sigma * sigma)));
    sum += weights.back();
  }
  ImageRgba8 out = image;
  for (int pass = 0; pass < 2; ++pass) {
    const ImageRgba8 in = out;
    for (int y = 0; y < in.height; ++y)
      for (int x = 0; x < in.width; ++x)
        for (int c = 0; c < 3; ++c) {
          double value = 0;
          for (int i = -radius; i <= radius; ++i) {
            const int sx = pass == 0 ? std::clamp(x + i, 0, in.width - 1) : x;
            const int sy = pass == 1 ? std::clamp(y + i, 0, in.height - 1) : y;
            value += weights[size_t(i + radius)] * in.at(sx, sy)[c];
          }
          out.at(x, y)[c] = uint8_t(std::lround(value / sum));
        }
  }
  return out;
}

TEST(Flip, IdenticalImagesHaveNoError) {
  const ImageRgba8 image = pattern(64, 1);
  EXPECT_EQ(flipMean(image, image), 0.0);
  for (float e : flipErrorMap(image, image)) EXPECT_EQ(e, 0.0f);
}

TEST(Flip, GreenAgainstBlueIsTheLargestError) {
  // The paper normalises colour differences by the Hunt-adjusted HyAB distance of green and
  // blue, so uniform green against uniform blue is exactly 1 (no features in either).
  EXPECT_NEAR(flipMean(uniform(32, 0, 255, 0), uniform(32, 0, 0, 255)), 1.0, 1e-6);
}

TEST(Flip, BlackAgainstWhiteFollowsTheRemapping) {
  // Black vs white: HyAB = |ΔL| = 100, so the error is (100^0.7 − pc·cmax) / (cmax − pc·cmax)
  // · (1 − pt) + pt with cmax = HyAB(green, blue)^0.7 from the published CIELAB values of
  // sRGB green (87.737, −86.185, 83.181) and blue (32.303, 79.197, −107.864): 0.9674. It lies in
  // the top band of the remapping (above pt = 0.95): near-maximal, but below green/blue.
  const double lg = 87.737, ag = -86.185 * lg / 100, bg = 83.181 * lg / 100;
  const double lb = 32.303, ab = 79.197 * lb / 100, bb = -107.864 * lb / 100;
  const double cmax = std::pow(std::abs(lg - lb) + std::hypot(ag - ab, bg - bb), 0.7);
  const double expected = 0.95 + (std::pow(100.0, 0.7) - 0.4 * cmax) / (0.6 * cmax) * 0.05;
  const double measured = flipMean(uniform(32, 0, 0, 0), uniform(32, 255, 255, 255));
  EXPECT_NEAR(measured, expected, 1e-3);
  EXPECT_GT(measured, 0.95);
  EXPECT_LT(measured, 1.0);
}

TEST(Flip, IsSymmetric) {
  const ImageRgba8 a = pattern(64, 2), b = pattern(64, 3);
  EXPECT_NEAR(flipMean(a, b), flipMean(b, a), 1e-6);
  const ImageRgba8 c = blurred(a, 1.5);
  EXPECT_NEAR(flipMean(a, c), flipMean(c, a), 1e-6);
}

TEST(Flip, GrowsWithBlurStrength) {
  const ImageRgba8 sharp = pattern(96, 4);
  double previous = 0.0;
  for (double sigma : {0.5, 1.0, 2.0, 4.0}) {
    const double error = flipMean(sharp, blurred(sharp, sigma));
    EXPECT_GT(error, previous) << "sigma " << sigma;
    previous = error;
  }
  EXPECT_LT(previous, 0.6);
}

TEST(Flip, ColourErrorGrowsWithTheDifference) {
  // Uniform images: no features, so FLIP is the remapped colour term alone, which grows with
  // the HyAB distance and stays far below the knee (0.95 at 40 % of the maximum) for a few steps.
  const ImageRgba8 grey = uniform(32, 128, 128, 128);
  double previous = 0.0;
  for (int step : {1, 4, 16, 64}) {
    const double error = flipMean(grey, uniform(32, uint8_t(128 + step), 128, 128));
    EXPECT_GT(error, previous) << step;
    previous = error;
  }
  EXPECT_LT(flipMean(grey, uniform(32, 129, 128, 128)), 0.05);
}

TEST(Flip, ErrorMapIsInRangeAndLocal) {
  // A change confined to one corner leaves the far corner (beyond every filter's reach) at 0.
  ImageRgba8 a = uniform(96, 100, 140, 90), b = a;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) b.at(x, y)[0] = 250;
  const std::vector<float> map = flipErrorMap(a, b);
  for (float e : map) {
    EXPECT_GE(e, 0.0f);
    EXPECT_LE(e, 1.0f);
  }
  EXPECT_GT(map[0], 0.3f);
  EXPECT_EQ(map[size_t(95) * 96 + 95], 0.0f);
}

}  // namespace
}  // namespace canopy

namespace canopy {
namespace {

TEST(Flip, APreparedReferenceScoresLikeTheOneShotCall) {
  const ImageRgba8 a = pattern(64, 5), b = pattern(64, 6);
  const FlipReference reference(a);
  EXPECT_DOUBLE_EQ(reference.meanError(b), flipMean(a, b));
  EXPECT_EQ(reference.errorMap(b), flipErrorMap(a, b));
  EXPECT_EQ(reference.meanError(a), 0.0);
}

}  // namespace
}  // namespace canopy
