#pragma once

#include <cmath>

#include "common/flip.h"
#include "common/image.h"

namespace canopy {

// PSNR of identical images is infinite; it is reported as this cap (an MSE of 255²·10⁻¹⁰).
inline constexpr double kPsnrCapDb = 100.0;

// The image metrics of DESIGN.md. Both images are composited over the same background and
// encoded to 8-bit sRGB; their alpha channel holds the coverage (0..255).
struct ImageMetrics {
  double psnr = 0.0;           // dB, MSE over RGB in the union of both coverage masks (alpha > 0)
  double psnrFrame = 0.0;      // dB, MSE over RGB of the whole frame
  double ssim = 0.0;           // mean SSIM of luma over the bounding box of the union mask
  double coverageError = 0.0;  // mean |alpha_ref − alpha| / 255 over the union mask
  double coverageErrorFrame = 0.0;  // mean |alpha_ref − alpha| / 255 over the whole frame
  double flip = std::nan("");       // LDR-FLIP, mean over the frame (NaN when not asked for)
  long unionPixels = 0;             // pixels in the union mask
};

// `flipPixelsPerDegree` > 0 also computes FLIP at that viewing condition (common/flip.h).
ImageMetrics compareImages(const ImageRgba8& reference, const ImageRgba8& image,
                           double flipPixelsPerDegree = 0.0);
// The same against a reference prepared once for FLIP (its image is the reference).
ImageMetrics compareImages(const FlipReference& reference, const ImageRgba8& image);

// 10·log10(255² / mse), capped at kPsnrCapDb.
double psnrFromMse(double mse);

// Mean SSIM (Wang et al. 2004: 11×11 Gaussian window, σ = 1.5, K1 = 0.01, K2 = 0.03) of the luma
// of two images over the pixel rectangle [x0, x1) × [y0, y1).
double ssimLuma(const ImageRgba8& a, const ImageRgba8& b, int x0, int y0, int x1, int y1);

}  // namespace canopy
