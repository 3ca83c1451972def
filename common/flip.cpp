#include "common/flip.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <numeric>

#include "common/image.h"

namespace canopy {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Parameters of LDR-FLIP as the paper gives them.
constexpr double kQc = 0.7;       // exponent of the colour difference
constexpr double kPc = 0.4;       // breakpoint of the colour remapping (share of the maximum) ...
constexpr double kPt = 0.95;      // ... and the error it maps to
constexpr double kQf = 0.5;       // exponent of the feature difference
constexpr double kWidth = 0.082;  // feature width (degrees of visual angle)

// Contrast sensitivity as sums of Gaussians in frequency, a1·exp(−b1 ρ²) + a2·exp(−b2 ρ²), for the
// achromatic, red-green and blue-yellow channels of YCxCz; in the spatial domain each term is
// a·sqrt(π/b)·exp(−π² x² / b) with x in degrees.
struct CsfTerm {
  double a, b;
};
constexpr std::array<std::array<CsfTerm, 2>, 3> kCsf = {{
    {{{1.0, 0.0047}, {0.0, 1e-5}}},   // achromatic
    {{{1.0, 0.0053}, {0.0, 1e-5}}},   // red-green
    {{{34.1, 0.04}, {13.5, 0.025}}},  // blue-yellow
}};

// Linear sRGB (D65) ↔ CIE XYZ.
constexpr float kRgbToXyz[3][3] = {{0.4124564, 0.3575761, 0.1804375},
                                   {0.2126729, 0.7151522, 0.0721750},
                                   {0.0193339, 0.1191920, 0.9503041}};
constexpr float kXyzToRgb[3][3] = {{3.2404542, -1.5371385, -0.4985314},
                                   {-0.9692660, 1.8760108, 0.0415560},
                                   {0.0556434, -0.2040259, 1.0572252}};

// Per-pixel colour math in float: the inputs are 8-bit, float's 24 bits are plenty.
struct Vec3 {
  float x, y, z;
};

Vec3 multiply(const float m[3][3], Vec3 v) {
  return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
          m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
          m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

// The reference white: XYZ of linear RGB (1, 1, 1).
const Vec3 kWhite = multiply(kRgbToXyz, {1.0f, 1.0f, 1.0f});

Vec3 xyzToYcxcz(Vec3 xyz) {
  const float y = xyz.y / kWhite.y;
  return {116.0f * y - 16.0f, 500.0f * (xyz.x / kWhite.x - y), 200.0f * (y - xyz.z / kWhite.z)};
}

Vec3 ycxczToXyz(Vec3 ycxcz) {
  const float y = (ycxcz.x + 16.0f) / 116.0f;
  return {(ycxcz.y / 500.0f + y) * kWhite.x, y * kWhite.y, (y - ycxcz.z / 200.0f) * kWhite.z};
}

float labF(float t) {
  constexpr float kDelta = 6.0f / 29.0f;
  return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3.0f * kDelta * kDelta) + 4.0f / 29.0f;
}

// Linear RGB → CIELAB, then the Hunt adjustment of the chroma (a, b scaled by 0.01·L).
Vec3 huntLab(Vec3 rgb) {
  const Vec3 xyz = multiply(kRgbToXyz, rgb);
  const float fx = labF(xyz.x / kWhite.x), fy = labF(xyz.y / kWhite.y), fz = labF(xyz.z / kWhite.z);
  const float l = 116.0f * fy - 16.0f;
  return {l, 0.01f * l * 500.0f * (fx - fy), 0.01f * l * 200.0f * (fy - fz)};
}

float hyab(Vec3 a, Vec3 b) {
  return std::abs(a.x - b.x) + std::hypot(a.y - b.y, a.z - b.z);
}

// The largest colour difference: Hunt-adjusted green against blue.
const double kMaxColorDifference =
    std::pow(double(hyab(huntLab({0.0f, 1.0f, 0.0f}), huntLab({0.0f, 0.0f, 1.0f}))), kQc);

// One channel of an image as floats.
struct Plane {
  int width = 0, height = 0;
  std::vector<float> values;
  Plane(int w, int h) : width(w), height(h), values(size_t(w) * h, 0.0f) {}
  float& at(int x, int y) { return values[size_t(y) * width + x]; }
  float at(int x, int y) const { return values[size_t(y) * width + x]; }
};

// Convolves along x (alongY false) or y with a kernel of radius (kernel.size() − 1) / 2,
// repeating the border pixels. The innermost loops run along rows, so they vectorise.
Plane convolve(const Plane& in, const std::vector<float>& kernel, bool alongY) {
  Plane out(in.width, in.height);
  const int radius = static_cast<int>(kernel.size() / 2), w = in.width, h = in.height;
  tbb::parallel_for(0, h, [&](int y) {
    float* dst = &out.values[size_t(y) * w];
    if (alongY) {
      for (int k = -radius; k <= radius; ++k) {
        const float weight = kernel[k + radius];
        const float* src = &in.values[size_t(std::clamp(y + k, 0, h - 1)) * w];
        for (int x = 0; x < w; ++x) dst[x] += weight * src[x];
      }
      return;
    }
    const float* src = &in.values[size_t(y) * w];
    // Interior pixels, whose taps all lie inside the row; then the borders, clamped.
    const int x0 = std::min(radius, w), x1 = std::max(x0, w - radius);
    for (int k = -radius; k <= radius; ++k) {
      const float weight = kernel[k + radius];
      for (int x = x0; x < x1; ++x) dst[x] += weight * src[x + k];
    }
    const auto clamped = [&](int x) {
      float sum = 0.0f;
      for (int k = -radius; k <= radius; ++k)
        sum += kernel[k + radius] * src[std::clamp(x + k, 0, w - 1)];
      dst[x] = sum;
    };
    for (int x = 0; x < x0; ++x) clamped(x);
    for (int x = x1; x < w; ++x) clamped(x);
  });
  return out;
}

Plane separable(const Plane& in, const std::vector<float>& alongX,
                const std::vector<float>& alongY) {
  return convolve(convolve(in, alongX, false), alongY, true);
}

// The colour pipeline's filter of one YCxCz channel: Σ_terms w·e(x)·e(y) with
// e(t) = exp(−π² (t/ppd)² / b), normalised so the 2D kernel sums to 1.
Plane filterChannel(const Plane& in, const std::array<CsfTerm, 2>& terms, double ppd, int radius) {
  std::vector<std::vector<float>> kernels;
  std::vector<double> weights;
  double total = 0.0;
  for (const CsfTerm& term : terms) {
    if (term.a == 0.0) continue;
    std::vector<float> e(2 * static_cast<size_t>(radius) + 1);
    double sum = 0.0;
    for (int i = -radius; i <= radius; ++i) {
      const double x = double(i) / ppd;
      e[i + radius] = float(std::exp(-kPi * kPi * x * x / term.b));
      sum += e[i + radius];
    }
    const double weight = term.a * std::sqrt(kPi / term.b);
    total += weight * sum * sum;
    kernels.push_back(std::move(e));
    weights.push_back(weight);
  }
  Plane out(in.width, in.height);
  for (size_t t = 0; t < kernels.size(); ++t) {
    const Plane part = separable(in, kernels[t], kernels[t]);
    const auto w = float(weights[t] / total);
    for (size_t i = 0; i < out.values.size(); ++i) out.values[i] += w * part.values[i];
  }
  return out;
}

// Scales the positive weights of a kernel to sum to 1 and the negative ones to −1.
void normalizeSigned(std::vector<float>& kernel) {
  double positive = 0.0, negative = 0.0;
  for (float w : kernel) (w > 0 ? positive : negative) += w;
  for (float& w : kernel) {
    if (w > 0 && positive > 0) w = float(w / positive);
    if (w < 0 && negative < 0) w = float(w / -negative);
  }
}

struct Features {
  Plane edges, points;  // gradient magnitudes of the edge and point detectors
};

// Edges (first derivative of a Gaussian) and points (second derivative) of normalised luminance,
// σ = ½·w·ppd pixels; each 2D detector is the derivative along one axis times the Gaussian along
// the other, positive and negative weights normalised separately.
Features detectFeatures(const Plane& luminance, double ppd) {
  const double sigma = 0.5 * kWidth * ppd;
  const int radius = static_cast<int>(std::ceil(3.0 * sigma));
  std::vector<float> gauss(2 * static_cast<size_t>(radius) + 1), first(gauss.size()),
      second(gauss.size());
  double sum = 0.0;
  for (int i = -radius; i <= radius; ++i) {
    const double g = std::exp(-double(i * i) / (2.0 * sigma * sigma));
    gauss[i + radius] = float(g);
    first[i + radius] = float(-double(i) * g);
    second[i + radius] = float((double(i * i) / (sigma * sigma) - 1.0) * g);
    sum += g;
  }
  for (float& g : gauss) g = float(g / sum);
  normalizeSigned(first);
  normalizeSigned(second);
  const Plane smoothX = convolve(luminance, gauss, false),
              smoothY = convolve(luminance, gauss, true);
  const Plane edgeX = convolve(smoothY, first, false), edgeY = convolve(smoothX, first, true);
  const Plane pointX = convolve(smoothY, second, false), pointY = convolve(smoothX, second, true);
  Features f{Plane(luminance.width, luminance.height), Plane(luminance.width, luminance.height)};
  for (size_t i = 0; i < f.edges.values.size(); ++i) {
    f.edges.values[i] = std::hypot(edgeX.values[i], edgeY.values[i]);
    f.points.values[i] = std::hypot(pointX.values[i], pointY.values[i]);
  }
  return f;
}

}  // namespace

// An image in the paper's two forms: CSF-filtered Hunt-adjusted Lab (colour pipeline) and the
// features of its luminance (feature pipeline).
struct FlipReference::Prepared {
  Plane l, a, b;
  Features features;
};

namespace {

using Prepared = FlipReference::Prepared;

// One radius for every channel, from the widest spatial Gaussian (σ = sqrt(b / 2π²) degrees).
int csfRadiusFor(double ppd) {
  double widest = 0.0;
  for (const auto& channel : kCsf)
    for (const CsfTerm& term : channel)
      if (term.a != 0.0) widest = std::max(widest, term.b);
  return static_cast<int>(std::ceil(3.0 * std::sqrt(widest / (2.0 * kPi * kPi)) * ppd));
}

Prepared prepare(const ImageRgba8& image, double ppd) {
  const int csfRadius = csfRadiusFor(ppd);
  const int w = image.width, h = image.height;
  std::array<float, 256> decode{};
  for (int v = 0; v < 256; ++v) decode[size_t(v)] = srgbToLinear(float(v) / 255.0f);
  std::array<Plane, 3> ycxcz = {Plane(w, h), Plane(w, h), Plane(w, h)};
  Plane luminance(w, h);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = image.at(x, y);
      const Vec3 c = xyzToYcxcz(multiply(kRgbToXyz, {decode[p[0]], decode[p[1]], decode[p[2]]}));
      ycxcz[0].at(x, y) = c.x;
      ycxcz[1].at(x, y) = c.y;
      ycxcz[2].at(x, y) = c.z;
      luminance.at(x, y) = (c.x + 16.0f) / 116.0f;
    }
  });
  std::array<Plane, 3> filtered = {filterChannel(ycxcz[0], kCsf[0], ppd, csfRadius),
                                   filterChannel(ycxcz[1], kCsf[1], ppd, csfRadius),
                                   filterChannel(ycxcz[2], kCsf[2], ppd, csfRadius)};
  Prepared out{Plane(w, h), Plane(w, h), Plane(w, h), detectFeatures(luminance, ppd)};
  tbb::parallel_for(size_t(0), out.l.values.size(), [&](size_t i) {
    Vec3 rgb =
        multiply(kXyzToRgb,
                 ycxczToXyz({filtered[0].values[i], filtered[1].values[i], filtered[2].values[i]}));
    rgb = {std::clamp(rgb.x, 0.0f, 1.0f), std::clamp(rgb.y, 0.0f, 1.0f),
           std::clamp(rgb.z, 0.0f, 1.0f)};
    const Vec3 lab = huntLab(rgb);
    out.l.values[i] = lab.x;
    out.a.values[i] = lab.y;
    out.b.values[i] = lab.z;
  });
  return out;
}

// The colour error remapped to [0, 1]: linear up to pc·cmax (where it reaches pt), then the rest.
float remapColorError(float difference) {
  const float e = std::pow(difference, float(kQc)), knee = float(kPc * kMaxColorDifference);
  if (e < knee) return float(kPt) / knee * e;
  return std::min(1.0f,
                  float(kPt) + (e - knee) / (float(kMaxColorDifference) - knee) * float(1.0 - kPt));
}

}  // namespace

FlipReference::FlipReference(const ImageRgba8& reference, double pixelsPerDegree)
    : mImage(reference),
      mPixelsPerDegree(pixelsPerDegree),
      mPrepared(std::make_unique<Prepared>(prepare(reference, pixelsPerDegree))) {}

FlipReference::~FlipReference() = default;
FlipReference::FlipReference(FlipReference&&) noexcept = default;
FlipReference& FlipReference::operator=(FlipReference&&) noexcept = default;

std::vector<float> FlipReference::errorMap(const ImageRgba8& test) const {
  assert(mImage.width == test.width && mImage.height == test.height);
  const size_t pixels = size_t(mImage.width) * mImage.height;
  std::vector<float> errors(pixels, 0.0f);
  if (pixels == 0 || mImage.pixels == test.pixels) return errors;  // identical: 0 everywhere
  const Prepared& r = *mPrepared;
  const Prepared t = prepare(test, mPixelsPerDegree);
  tbb::parallel_for(size_t(0), pixels, [&](size_t i) {
    const float color = remapColorError(hyab({r.l.values[i], r.a.values[i], r.b.values[i]},
                                             {t.l.values[i], t.a.values[i], t.b.values[i]}));
    const float featureDifference =
        std::max(std::abs(r.features.edges.values[i] - t.features.edges.values[i]),
                 std::abs(r.features.points.values[i] - t.features.points.values[i]));
    const float feature = std::pow(std::min(1.0f, featureDifference / std::sqrt(2.0f)), float(kQf));
    errors[i] = std::pow(color, 1.0f - feature);
  });
  return errors;
}

double FlipReference::meanError(const ImageRgba8& test) const {
  const std::vector<float> errors = errorMap(test);
  if (errors.empty()) return 0.0;
  return std::accumulate(errors.begin(), errors.end(), 0.0) / double(errors.size());
}

std::vector<float> flipErrorMap(const ImageRgba8& reference, const ImageRgba8& test,
                                double pixelsPerDegree) {
  if (reference.pixels == test.pixels)  // identical: skip the preparation too
    return std::vector<float>(size_t(reference.width) * reference.height, 0.0f);
  return FlipReference(reference, pixelsPerDegree).errorMap(test);
}

double flipMean(const ImageRgba8& reference, const ImageRgba8& test, double pixelsPerDegree) {
  if (reference.pixels == test.pixels) return 0.0;
  return FlipReference(reference, pixelsPerDegree).meanError(test);
}

}  // namespace canopy
