#include "common/metrics.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

namespace canopy {
namespace {

ImageRgba8 filled(int w, int h, uint8_t r, uint8_t g, uint8_t b, uint8_t a) {
  ImageRgba8 image(w, h);
  for (int i = 0; i < w * h; ++i) {
    image.pixels[i * 4 + 0] = r;
    image.pixels[i * 4 + 1] = g;
    image.pixels[i * 4 + 2] = b;
    image.pixels[i * 4 + 3] = a;
  }
  return image;
}

TEST(Metrics, PsnrOverUnionMaskAndFrameMatchHandComputedValues) {
  // 4×4 images; the reference covers the left half, the method the top half. Union: 12 pixels.
  ImageRgba8 reference = filled(4, 4, 100, 100, 100, 0), method = reference;
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) {
      if (x < 2) reference.at(x, y)[3] = 255;
      if (y < 2) method.at(x, y)[3] = 255;
    }
  }
  // Colour differs by 10 in red on exactly 3 pixels, all inside the union.
  method.at(0, 0)[0] = 110;
  method.at(3, 0)[0] = 110;
  method.at(1, 3)[0] = 110;
  const ImageMetrics m = compareImages(reference, method);
  EXPECT_EQ(m.unionPixels, 12);
  // MSE over the union: 3 pixels × 100 / (12 pixels × 3 channels).
  EXPECT_NEAR(m.psnr, 10.0 * std::log10(255.0 * 255.0 / (300.0 / 36.0)), 1e-9);
  EXPECT_NEAR(m.psnrFrame, 10.0 * std::log10(255.0 * 255.0 / (300.0 / 48.0)), 1e-9);
  // Coverage: pixels in exactly one mask (4 + 4 = 8 of 12) differ by 1.
  EXPECT_NEAR(m.coverageError, 8.0 / 12.0, 1e-12);
}

TEST(Metrics, IdenticalImagesHitTheCapAndSsimOne) {
  ImageRgba8 image = filled(32, 32, 40, 120, 30, 255);
  image.at(5, 5)[1] = 200;
  const ImageMetrics m = compareImages(image, image);
  EXPECT_DOUBLE_EQ(m.psnr, kPsnrCapDb);
  EXPECT_NEAR(m.ssim, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(m.coverageError, 0.0);
}

TEST(Metrics, SsimOfConstantImagesIsTheLuminanceTerm) {
  // Constant images: variances and covariance vanish, so SSIM = (2ab + C1) / (a² + b² + C1).
  const ImageRgba8 a = filled(24, 24, 100, 100, 100, 255), b = filled(24, 24, 150, 150, 150, 255);
  const double c1 = std::pow(0.01 * 255.0, 2);
  const double expected = (2.0 * 100 * 150 + c1) / (100.0 * 100 + 150.0 * 150 + c1);
  EXPECT_NEAR(ssimLuma(a, b, 0, 0, 24, 24), expected, 1e-4);
}

TEST(Metrics, SsimDropsWithNoise) {
  ImageRgba8 a = filled(64, 64, 90, 90, 90, 255), b = a;
  for (int i = 0; i < 64 * 64; ++i) {
    const uint8_t v = static_cast<uint8_t>((i * 37) % 200);
    a.pixels[i * 4] = a.pixels[i * 4 + 1] = a.pixels[i * 4 + 2] = v;
    b.pixels[i * 4] = b.pixels[i * 4 + 1] = b.pixels[i * 4 + 2] = static_cast<uint8_t>(200 - v);
  }
  EXPECT_LT(ssimLuma(a, b, 0, 0, 64, 64), 0.0);  // anti-correlated structure
}

TEST(Metrics, BoxDownsampleAveragesBlocksAndCompositingUsesCoverage) {
  ImageRgbaF image(2, 2);
  image.at(0, 0)[3] = 1.0f;  // one of four subsamples covered, premultiplied white
  image.at(0, 0)[0] = image.at(0, 0)[1] = image.at(0, 0)[2] = 1.0f;
  const ImageRgbaF small = boxDownsample(image, 2);
  ASSERT_EQ(small.width, 1);
  EXPECT_FLOAT_EQ(small.at(0, 0)[3], 0.25f);
  EXPECT_FLOAT_EQ(small.at(0, 0)[0], 0.25f);
  const ImageRgba8 out = compositeToSrgb8(small, glm::vec3(0.0f));
  EXPECT_EQ(out.at(0, 0)[0], encodeSrgb8(0.25f));
  EXPECT_EQ(out.at(0, 0)[3], 64);
}

}  // namespace
}  // namespace canopy

namespace canopy {
namespace {

TEST(ImageIo, PngRoundTripKeepsStraightAlphaExactly) {
  ImageRgba8 image(16, 4);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = static_cast<uint8_t>((i * 53) % 256);
  const auto path = std::filesystem::temp_directory_path() /
                    ("canopy_png_" + std::to_string(::getpid()) + ".png");
  writePng(path, image);
  const ImageRgba8 back = readImage(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back, image);
}

}  // namespace
}  // namespace canopy
