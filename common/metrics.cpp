#include "common/metrics.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

#include "common/flip.h"

namespace canopy {

double psnrFromMse(double mse) {
  const double floor = 255.0 * 255.0 * std::pow(10.0, -kPsnrCapDb / 10.0);
  return 10.0 * std::log10(255.0 * 255.0 / std::max(mse, floor));
}

namespace {

std::vector<double> lumaOf(const ImageRgba8& image) {
  std::vector<double> luma(size_t(image.width) * image.height);
  for (size_t i = 0; i < luma.size(); ++i) {
    const uint8_t* p = &image.pixels[i * 4];
    luma[i] = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
  }
  return luma;
}

// One pass of the 11-tap Gaussian (σ = 1.5) along x (step 1) or y (step width), with the window
// clipped and renormalised at the image border.
std::vector<double> gaussianPass(const std::vector<double>& input, int width, int height,
                                 bool alongY) {
  constexpr int kRadius = 5;
  constexpr double kSigma = 1.5;
  double weights[2 * kRadius + 1];
  for (int i = -kRadius; i <= kRadius; ++i) {
    weights[i + kRadius] = std::exp(-double(i * i) / (2 * kSigma * kSigma));
  }
  std::vector<double> output(input.size());
  const int length = alongY ? height : width;
  const size_t step = alongY ? size_t(width) : 1;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int position = alongY ? y : x;
      const size_t centre = size_t(y) * width + x;
      double sum = 0, norm = 0;
      for (int k = -kRadius; k <= kRadius; ++k) {
        if (position + k < 0 || position + k >= length) continue;
        sum += weights[k + kRadius] * input[centre + k * static_cast<std::ptrdiff_t>(step)];
        norm += weights[k + kRadius];
      }
      output[centre] = sum / norm;
    }
  }
  return output;
}

std::vector<double> gaussianBlur(const std::vector<double>& input, int width, int height) {
  return gaussianPass(gaussianPass(input, width, height, false), width, height, true);
}

}  // namespace

double ssimLuma(const ImageRgba8& a, const ImageRgba8& b, int x0, int y0, int x1, int y1) {
  assert(a.width == b.width && a.height == b.height);
  if (x1 <= x0 || y1 <= y0) return std::numeric_limits<double>::quiet_NaN();
  // Work on the rectangle grown by the window radius so windows inside it see real pixels.
  const int gx0 = std::max(0, x0 - 5), gy0 = std::max(0, y0 - 5);
  const int gx1 = std::min(a.width, x1 + 5), gy1 = std::min(a.height, y1 + 5);
  const int w = gx1 - gx0, h = gy1 - gy0;
  const std::vector<double> lumaA = lumaOf(a), lumaB = lumaOf(b);
  std::vector<double> pa(size_t(w) * h), pb(pa.size()), paa(pa.size()), pbb(pa.size()),
      pab(pa.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t src = size_t(y + gy0) * a.width + (x + gx0), dst = size_t(y) * w + x;
      pa[dst] = lumaA[src];
      pb[dst] = lumaB[src];
      paa[dst] = lumaA[src] * lumaA[src];
      pbb[dst] = lumaB[src] * lumaB[src];
      pab[dst] = lumaA[src] * lumaB[src];
    }
  }
  const auto ma = gaussianBlur(pa, w, h), mb = gaussianBlur(pb, w, h);
  const auto maa = gaussianBlur(paa, w, h), mbb = gaussianBlur(pbb, w, h),
             mab = gaussianBlur(pab, w, h);
  const double c1 = std::pow(0.01 * 255.0, 2), c2 = std::pow(0.03 * 255.0, 2);
  double sum = 0.0;
  long count = 0;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const size_t i = size_t(y - gy0) * w + (x - gx0);
      const double muA = ma[i], muB = mb[i];
      const double varA = std::max(0.0, double(maa[i]) - muA * muA);
      const double varB = std::max(0.0, double(mbb[i]) - muB * muB);
      const double cov = double(mab[i]) - muA * muB;
      sum += ((2 * muA * muB + c1) * (2 * cov + c2)) /
             ((muA * muA + muB * muB + c1) * (varA + varB + c2));
      ++count;
    }
  }
  return sum / double(count);
}

namespace {
ImageMetrics compareWithoutFlip(const ImageRgba8& reference, const ImageRgba8& image);
}  // namespace

ImageMetrics compareImages(const ImageRgba8& reference, const ImageRgba8& image,
                           double flipPixelsPerDegree) {
  ImageMetrics metrics = compareWithoutFlip(reference, image);
  if (flipPixelsPerDegree > 0.0) metrics.flip = flipMean(reference, image, flipPixelsPerDegree);
  return metrics;
}

ImageMetrics compareImages(const FlipReference& reference, const ImageRgba8& image) {
  ImageMetrics metrics = compareWithoutFlip(reference.image(), image);
  metrics.flip = reference.meanError(image);
  return metrics;
}

namespace {
ImageMetrics compareWithoutFlip(const ImageRgba8& reference, const ImageRgba8& image) {
  assert(reference.width == image.width && reference.height == image.height);
  ImageMetrics metrics;
  double sumUnion = 0.0, sumFrame = 0.0, coverage = 0.0, coverageFrame = 0.0;
  int x0 = reference.width, y0 = reference.height, x1 = 0, y1 = 0;
  for (int y = 0; y < reference.height; ++y) {
    for (int x = 0; x < reference.width; ++x) {
      const uint8_t* r = reference.at(x, y);
      const uint8_t* m = image.at(x, y);
      double squared = 0.0;
      for (int c = 0; c < 3; ++c) squared += std::pow(double(r[c]) - double(m[c]), 2);
      sumFrame += squared;
      const double alphaError = std::abs(int(r[3]) - int(m[3])) / 255.0;
      coverageFrame += alphaError;
      if (r[3] > 0 || m[3] > 0) {
        sumUnion += squared;
        coverage += alphaError;
        ++metrics.unionPixels;
        x0 = std::min(x0, x);
        y0 = std::min(y0, y);
        x1 = std::max(x1, x + 1);
        y1 = std::max(y1, y + 1);
      }
    }
  }
  const double frameSamples = 3.0 * reference.width * reference.height;
  metrics.psnrFrame = psnrFromMse(sumFrame / frameSamples);
  metrics.coverageErrorFrame = coverageFrame / double(reference.width * reference.height);
  if (metrics.unionPixels == 0) {
    // Nothing drawn in either image: the images agree exactly.
    metrics.psnr = kPsnrCapDb;
    metrics.ssim = 1.0;
    return metrics;
  }
  metrics.psnr = psnrFromMse(sumUnion / (3.0 * metrics.unionPixels));
  metrics.coverageError = coverage / double(metrics.unionPixels);
  metrics.ssim = ssimLuma(reference, image, x0, y0, x1, y1);
  return metrics;
}
}  // namespace

}  // namespace canopy
