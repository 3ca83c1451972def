#include "common/capture_intrinsics.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>

#include "common/error.h"

namespace canopy {
namespace {

// A key of the frame, else of the file; a finite number when present.
std::optional<double> number(const nlohmann::json& file, const nlohmann::json& frame,
                             const char* key, const std::string& where) {
  const nlohmann::json* value = nullptr;
  if (frame.is_object() && frame.contains(key)) {
    value = &frame.at(key);
  } else if (file.is_object() && file.contains(key)) {
    value = &file.at(key);
  }
  if (!value) return std::nullopt;
  if (!value->is_number() || !std::isfinite(value->get<double>()))
    throwInputError("{}: {} = {} is not a finite number", where, key, value->dump());
  return value->get<double>();
}

// Focal length in pixels from a field of view in radians across `pixels`.
double focalFromAngle(double angle, int pixels, const char* key, const std::string& where) {
  if (!(angle > 0.0 && angle < 3.1))
    throwInputError("{}: {} = {} is not a field of view in radians", where, key, angle);
  return 0.5 * double(pixels) / std::tan(0.5 * angle);
}

}  // namespace

bool PinholeIntrinsics::isCentredSquare() const {
  return focalX == focalY && centerX == 0.5 * double(width) && centerY == 0.5 * double(height);
}

float CentredPinhole::fovYDegrees() const {
  return float(glm::degrees(2.0 * std::atan(0.5 * double(height) / focal)));
}

PinholeIntrinsics readIntrinsics(const nlohmann::json& file, const nlohmann::json& frame, int width,
                                 int height, const std::string& where) {
  PinholeIntrinsics k;
  k.width = width;
  k.height = height;
  for (const auto& [key, size] : {std::pair{"w", width}, std::pair{"h", height}}) {
    const auto value = number(file, frame, key, where);
    if (value && *value != double(size)) {
      throwInputError(
          "{}: {} = {}, but the image is {}×{} (resized images need their "
          "intrinsics scaled too)",
          where, key, *value, width, height);
    }
  }
  if (const auto* model = frame.contains("camera_model")  ? &frame.at("camera_model")
                          : file.contains("camera_model") ? &file.at("camera_model")
                                                          : nullptr) {
    const std::string name = model->is_string() ? model->get<std::string>() : model->dump();
    if (name != "PINHOLE" && name != "SIMPLE_PINHOLE" && name != "OPENCV") {
      throwInputError(
          "{}: camera_model {} is not a pinhole camera (PINHOLE, SIMPLE_PINHOLE, or "
          "OPENCV without distortion); undistort the images first",
          where, name);
    }
  }
  for (const char* key : {"k1", "k2", "k3", "k4", "p1", "p2"}) {
    const auto value = number(file, frame, key, where);
    if (value && *value != 0.0) {
      throwInputError(
          "{}: {} = {}: lens distortion is not modelled; undistort the images "
          "first (nerfstudio's or COLMAP's image_undistorter)",
          where, key, *value);
    }
  }
  const auto focal = [&](const char* focalKey, const char* angleKey, int pixels) {
    std::optional<double> value = number(file, frame, focalKey, where);
    if (value && !(*value > 0.0))
      throwInputError("{}: {} = {} must be a focal length > 0", where, focalKey, *value);
    if (!value) {
      if (const auto angle = number(file, frame, angleKey, where))
        value = focalFromAngle(*angle, pixels, angleKey, where);
    }
    return value;
  };
  const std::optional<double> focalX = focal("fl_x", "camera_angle_x", width);
  if (!focalX)
    throwInputError("{}: needs fl_x or camera_angle_x (the horizontal focal length)", where);
  k.focalX = *focalX;
  k.focalY = focal("fl_y", "camera_angle_y", height).value_or(k.focalX);  // else square pixels
  if (k.focalX > 16.0 * k.focalY || k.focalY > 16.0 * k.focalX)
    throwInputError("{}: fl_x = {} and fl_y = {} are no camera's", where, k.focalX, k.focalY);
  k.centerX = 0.5 * double(width);
  k.centerY = 0.5 * double(height);
  for (const auto& [key, center, size] :
       {std::tuple{"cx", &k.centerX, width}, std::tuple{"cy", &k.centerY, height}}) {
    if (const auto value = number(file, frame, key, where)) {
      if (!(*value > 0.0 && *value < double(size)))
        throwInputError("{}: {} = {} lies outside the image (0–{} pixels)", where, key, *value,
                        size);
      *center = *value;
    }
  }
  return k;
}

CentredPinhole commonCentredPinhole(std::span<const PinholeIntrinsics> frames) {
  const PinholeIntrinsics& first = frames.front();
  if (first.isCentredSquare() &&
      std::ranges::all_of(frames, [&](const PinholeIntrinsics& k) { return k == first; }))
    return {first.focalX, first.width, first.height};
  CentredPinhole to;
  double halfX = 0.0, halfY = 0.0;  // tangents of the half fields of view
  long largest = 0;
  for (const PinholeIntrinsics& k : frames) {
    to.focal = std::max({to.focal, k.focalX, k.focalY});
    halfX = std::max(halfX, std::max(k.centerX, k.width - k.centerX) / k.focalX);
    halfY = std::max(halfY, std::max(k.centerY, k.height - k.centerY) / k.focalY);
    largest = std::max(largest, long(k.width) * k.height);
  }
  to.width = 2 * int(std::ceil(halfX * to.focal - 1e-6));
  to.height = 2 * int(std::ceil(halfY * to.focal - 1e-6));
  if (long(to.width) * to.height > 16 * largest) {
    throwInputError(
        "the capture's intrinsics need a {}×{} centred image to hold every frame, "
        "over 16 times a frame's pixels",
        to.width, to.height);
  }
  return to;
}

ImageRgbaF resampleToCentred(ImageRgbaF image, const PinholeIntrinsics& from,
                             const CentredPinhole& to) {
  if (from.isCentredSquare() && from.focalX == to.focal && from.width == to.width &&
      from.height == to.height)
    return image;
  ImageRgbaF out(to.width, to.height);
  const auto texel = [&](int x, int y) -> const float* {
    static const float transparent[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    return x < 0 || y < 0 || x >= image.width || y >= image.height ? transparent : image.at(x, y);
  };
  for (int y = 0; y < to.height; ++y) {
    // The output pixel's ray in tangent space, then where it lands in the frame (pixel centres
    // at +0.5 in both).
    const double ty = (y + 0.5 - 0.5 * to.height) / to.focal;
    const double v = from.centerY + ty * from.focalY - 0.5;
    const int y0 = int(std::floor(v));
    const float fy = float(v - y0);
    for (int x = 0; x < to.width; ++x) {
      const double tx = (x + 0.5 - 0.5 * to.width) / to.focal;
      const double u = from.centerX + tx * from.focalX - 0.5;
      const int x0 = int(std::floor(u));
      const float fx = float(u - x0);
      float* p = out.at(x, y);
      const float* a = texel(x0, y0);
      const float* b = texel(x0 + 1, y0);
      const float* c = texel(x0, y0 + 1);
      const float* d = texel(x0 + 1, y0 + 1);
      for (int ch = 0; ch < 4; ++ch) {
        p[ch] = (1 - fy) * ((1 - fx) * a[ch] + fx * b[ch]) + fy * ((1 - fx) * c[ch] + fx * d[ch]);
      }
    }
  }
  return out;
}

}  // namespace canopy
