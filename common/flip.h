#pragma once

#include <memory>
#include <vector>

#include "common/image.h"

namespace canopy {

// LDR-FLIP (Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild: "FLIP: A Difference
// Evaluator for Alternating Images", Proc. ACM CGIT 3(2), HPG 2020), written from the paper's
// equations. Per pixel, in [0, 1]: the colour difference of the two images after spatial
// filtering by the contrast sensitivity of a viewer at `pixelsPerDegree` (Hunt-adjusted HyAB
// distance, remapped so that green vs blue, the largest difference, is 1) raised to the power
// 1 − the feature difference (edges and points of the luminance). Identical images give 0.
//
// The viewing condition sets the filters' sizes: the paper's default is 67 pixels per degree
// (a 0.7 m wide 3840-pixel monitor seen from 0.7 m). Image borders repeat the edge pixels.
inline constexpr double kFlipDefaultPixelsPerDegree = 67.0;

// A reference image prepared once (its filtered colours and features) for scoring many test
// images against it: half of FLIP's work is the reference's, the same for every method.
class FlipReference {
 public:
  FlipReference(const ImageRgba8& reference, double pixelsPerDegree = kFlipDefaultPixelsPerDegree);
  ~FlipReference();
  FlipReference(FlipReference&&) noexcept;
  FlipReference& operator=(FlipReference&&) noexcept;

  const ImageRgba8& image() const { return mImage; }
  double pixelsPerDegree() const { return mPixelsPerDegree; }
  std::vector<float> errorMap(const ImageRgba8& test) const;  // see flipErrorMap
  double meanError(const ImageRgba8& test) const;             // see flipMean

  struct Prepared;  // defined in flip.cpp

 private:
  ImageRgba8 mImage;
  double mPixelsPerDegree;
  std::unique_ptr<Prepared> mPrepared;
};

// The per-pixel error map of two images of the same size (8-bit sRGB RGB; alpha is ignored, so
// compose them over the same background first), row-major.
std::vector<float> flipErrorMap(const ImageRgba8& reference, const ImageRgba8& test,
                                double pixelsPerDegree = kFlipDefaultPixelsPerDegree);

// The mean of the error map over the frame: the number FLIP reports.
double flipMean(const ImageRgba8& reference, const ImageRgba8& test,
                double pixelsPerDegree = kFlipDefaultPixelsPerDegree);

}  // namespace canopy
