#pragma once

#include <span>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "common/image.h"

namespace canopy {

// A frame's pinhole intrinsics in pixels: focal lengths, principal point (x right, y down from
// the image's top-left corner) and image size, as nerfstudio and instant-ngp write them.
struct PinholeIntrinsics {
  double focalX = 0.0, focalY = 0.0;
  double centerX = 0.0, centerY = 0.0;
  int width = 0, height = 0;
  // Principal point at the image centre and square pixels: the camera a Canopy Camera is.
  bool isCentredSquare() const;
  bool operator==(const PinholeIntrinsics&) const = default;
};

// The intrinsics of one frame of a transforms file for an image of width × height: the frame's
// own keys over the file's top-level ones — fl_x, fl_y, cx, cy, w, h (nerfstudio, instant-ngp),
// or camera_angle_x (and camera_angle_y) in radians with the principal point at the centre.
// Throws InputError naming `where` and the key for a value that is not a finite number or out of
// range, a w/h that is not the image's size, lens distortion (k1…k4, p1, p2 non-zero) or a camera
// model other than a pinhole.
PinholeIntrinsics readIntrinsics(const nlohmann::json& file, const nlohmann::json& frame, int width,
                                 int height, const std::string& where);

// A camera with square pixels and its principal point at the centre.
struct CentredPinhole {
  double focal = 0.0;  // pixels
  int width = 0, height = 0;
  float fovYDegrees() const;
};

// The centred camera all frames are resampled to: the largest focal length of any frame (no
// frame loses resolution) and an even size that holds every frame's field of view. Frames that
// are already centred, square and alike keep their own camera (no resampling at all). Throws
// InputError when the frames would need an image over 16 times their own.
CentredPinhole commonCentredPinhole(std::span<const PinholeIntrinsics> frames);

// `image`, taken with `from`, as the centred camera `to` with the same pose sees it: bilinear on
// linear premultiplied values, transparent where `from` saw nothing (a capture shows the whole
// object in every frame). The image itself, untouched, when `from` already is `to`.
ImageRgbaF resampleToCentred(ImageRgbaF image, const PinholeIntrinsics& from,
                             const CentredPinhole& to);

}  // namespace canopy
