#include "common/captures.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/capture_intrinsics.h"
#include "common/config.h"
#include "common/error.h"
#include "common/file_checks.h"

namespace canopy {

PixelCamera::PixelCamera(const Camera& camera, int width, int height)
    : mWidth(width), mHeight(height), mPosition(camera.position) {
  mForward = glm::normalize(camera.target - camera.position);
  mRight = glm::normalize(glm::cross(mForward, camera.up));
  mUp = glm::cross(mRight, mForward);
  mFocal = 0.5f * float(height) / std::tan(0.5f * glm::radians(camera.fovYDegrees));
}

glm::vec2 PixelCamera::project(const glm::vec3& point) const {
  const glm::vec3 d = point - mPosition;
  const float z = glm::dot(d, mForward);
  return {0.5f * float(mWidth) + mFocal * glm::dot(d, mRight) / z,
          0.5f * float(mHeight) - mFocal * glm::dot(d, mUp) / z};
}

glm::vec3 PixelCamera::rayDirection(glm::vec2 pixel) const {
  return glm::normalize(mForward * mFocal + mRight * (pixel.x - 0.5f * float(mWidth)) -
                        mUp * (pixel.y - 0.5f * float(mHeight)));
}

AlphaIntegral::AlphaIntegral(const ImageRgbaF& image, float foregroundAlpha)
    : mWidth(image.width), mHeight(image.height) {
  const size_t stride = size_t(mWidth) + 1;
  mAlpha.assign(stride * (size_t(mHeight) + 1), 0.0);
  mForeground.assign(mAlpha.size(), 0);
  for (int y = 0; y < mHeight; ++y) {
    double rowAlpha = 0.0;
    uint32_t rowCount = 0;
    for (int x = 0; x < mWidth; ++x) {
      const float a = image.at(x, y)[3];
      rowAlpha += a;
      rowCount += a > foregroundAlpha ? 1 : 0;
      const size_t i = (size_t(y) + 1) * stride + size_t(x) + 1;
      mAlpha[i] = mAlpha[i - stride] + rowAlpha;
      mForeground[i] = mForeground[i - stride] + rowCount;
    }
  }
}

namespace {
template <typename T>
T rectSum(const std::vector<T>& table, int width, int height, int x0, int y0, int x1, int y1) {
  x0 = std::clamp(x0, 0, width), x1 = std::clamp(x1, 0, width);
  y0 = std::clamp(y0, 0, height), y1 = std::clamp(y1, 0, height);
  if (x1 <= x0 || y1 <= y0) return T(0);
  const size_t stride = size_t(width) + 1;
  return table[size_t(y1) * stride + x1] - table[size_t(y0) * stride + x1] -
         table[size_t(y1) * stride + x0] + table[size_t(y0) * stride + x0];
}
}  // namespace

double AlphaIntegral::alphaSum(int x0, int y0, int x1, int y1) const {
  return rectSum(mAlpha, mWidth, mHeight, x0, y0, x1, y1);
}

uint32_t AlphaIntegral::foregroundCount(int x0, int y0, int x1, int y1) const {
  return rectSum(mForeground, mWidth, mHeight, x0, y0, x1, y1);
}

namespace {
// The bounding rectangle (pixel coordinates) of a box's projection; false when a corner is behind
// the camera.
bool projectedBounds(const PixelCamera& camera, const Aabb& box, glm::vec2& lo, glm::vec2& hi) {
  lo = glm::vec2(std::numeric_limits<float>::max());
  hi = glm::vec2(std::numeric_limits<float>::lowest());
  for (int c = 0; c < 8; ++c) {
    const glm::vec3 corner(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                           c & 4 ? box.max.z : box.min.z);
    if (camera.depth(corner) <= 1e-6f) return false;
    const glm::vec2 p = camera.project(corner);
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return true;
}
}  // namespace

bool projectBoxInside(const PixelCamera& camera, const Aabb& box, PixelRect& rect) {
  glm::vec2 lo, hi;
  if (!projectedBounds(camera, box, lo, hi)) return false;
  if (lo.x < 0.0f || lo.y < 0.0f || hi.x > float(camera.width()) || hi.y > float(camera.height()))
    return false;
  rect = {int(std::floor(lo.x)), int(std::floor(lo.y)), int(std::ceil(hi.x)), int(std::ceil(hi.y))};
  rect.x1 = std::max(rect.x1, rect.x0 + 1);
  rect.y1 = std::max(rect.y1, rect.y0 + 1);
  return true;
}

bool viewCarvesBox(const PixelCamera& camera, const AlphaIntegral& mask, const Aabb& box) {
  glm::vec2 lo, hi;
  if (!projectedBounds(camera, box, lo, hi)) return false;
  if (hi.x <= 0.0f || hi.y <= 0.0f || lo.x >= float(camera.width()) ||
      lo.y >= float(camera.height()))
    return true;
  PixelRect r;
  return projectBoxInside(camera, box, r) && mask.foregroundCount(r.x0, r.y0, r.x1, r.y1) == 0;
}

Camera cameraFromNerf(const glm::mat4& cameraToWorld, float cameraAngleX, int width, int height) {
  Camera camera;
  camera.position = glm::vec3(cameraToWorld[3]);
  const glm::vec3 forward = -glm::normalize(glm::vec3(cameraToWorld[2]));
  camera.target = camera.position + forward;
  camera.up = glm::normalize(glm::vec3(cameraToWorld[1]));
  const float tanHalfX = std::tan(0.5f * cameraAngleX);
  camera.fovYDegrees = glm::degrees(2.0f * std::atan(tanHalfX * float(height) / float(width)));
  return camera;
}

ImageRgbaF toLinearPremultiplied(const ImageRgba8& image) {
  ImageRgbaF out(image.width, image.height);
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i) {
    const float a = image.pixels[i * 4 + 3] / 255.0f;
    for (int c = 0; c < 3; ++c)
      out.pixels[i * 4 + c] = srgbToLinear(image.pixels[i * 4 + c] / 255.0f) * a;
    out.pixels[i * 4 + 3] = a;
  }
  return out;
}

ImageRgba8 toStraightSrgb8(const ImageRgbaF& image) {
  ImageRgba8 out(image.width, image.height);
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i) {
    const float a = std::clamp(image.pixels[i * 4 + 3], 0.0f, 1.0f);
    for (int c = 0; c < 3; ++c)
      out.pixels[i * 4 + c] =
          a > 0.0f ? encodeSrgb8(std::clamp(image.pixels[i * 4 + c] / a, 0.0f, 1.0f)) : 0;
    out.pixels[i * 4 + 3] = uint8_t(std::lround(a * 255.0f));
  }
  return out;
}

void writeNerfCaptures(const std::filesystem::path& folder, const std::vector<CapturedView>& train,
                       const std::vector<CapturedView>& test) {
  for (const auto& [split, views] :
       {std::pair{std::string("train"), &train}, std::pair{std::string("test"), &test}}) {
    nlohmann::json json = {{"frames", nlohmann::json::array()}};
    for (size_t i = 0; i < views->size(); ++i) {
      const CapturedView& v = (*views)[i];
      const float tanHalfY = std::tan(0.5f * glm::radians(v.camera.fovYDegrees));
      json["camera_angle_x"] =
          2.0f * std::atan(tanHalfY * float(v.image.width) / float(v.image.height));
      const glm::mat4 cameraToWorld = glm::inverse(v.camera.view());
      nlohmann::json rows = nlohmann::json::array();
      for (int r = 0; r < 4; ++r)
        rows.push_back(
            {cameraToWorld[0][r], cameraToWorld[1][r], cameraToWorld[2][r], cameraToWorld[3][r]});
      const std::string file = split + "/r_" + std::to_string(i);
      writePng(folder / (file + ".png"), toStraightSrgb8(v.image));
      json["frames"].push_back({{"file_path", "./" + file}, {"transform_matrix", rows}});
    }
    writeTextAtomically(folder / ("transforms_" + split + ".json"), json.dump(2));
  }
}

namespace {

// A frame's camera-to-world matrix: 4×4 finite numbers, last row (0 0 0 1), and a 3×3 part of
// full rank (its columns are the camera's right, up and backward axes, however scaled).
glm::mat4 readCameraToWorld(const nlohmann::json& m, const std::string& where) {
  const auto notFourByFour = [&] { throwInputError("{} must be 4×4 numbers", where); };
  if (!m.is_array() || m.size() != 4) notFourByFour();
  glm::mat4 cameraToWorld(1.0f);
  for (int r = 0; r < 4; ++r) {
    if (!m[r].is_array() || m[r].size() != 4) notFourByFour();
    for (int c = 0; c < 4; ++c) {
      if (!m[r][c].is_number()) notFourByFour();
      const float value = m[r][c].get<float>();
      if (!std::isfinite(value)) throwInputError("{} has a non-finite entry", where);
      cameraToWorld[c][r] = value;  // JSON rows, glm columns
    }
  }
  if (glm::vec4(m[3][0].get<float>(), m[3][1].get<float>(), m[3][2].get<float>(),
                m[3][3].get<float>()) != glm::vec4(0, 0, 0, 1))
    throwInputError("{}: last row must be [0, 0, 0, 1] (a camera pose)", where);
  const glm::mat3 axes(cameraToWorld);
  const float scale = glm::length(axes[0]) * glm::length(axes[1]) * glm::length(axes[2]);
  if (!(scale > 0.0f) || std::abs(glm::determinant(axes)) < 1e-3f * scale)
    throwInputError("{}: its 3×3 part has rank below 3 (no camera orientation)", where);
  return cameraToWorld;
}

// A frame as the transforms file gives it, before its image is brought to a centred camera.
struct TransformsFrame {
  glm::mat4 cameraToWorld;
  PinholeIntrinsics intrinsics;
  ImageRgbaF image;
  std::string name;
};

std::vector<TransformsFrame> readTransforms(const std::filesystem::path& folder,
                                            const std::string& fileName, glm::ivec2& size) {
  const std::filesystem::path path = folder / fileName;
  if (!pathExists(path))
    throwInputError("{}: missing (a NeRF capture folder needs it)", path.string());
  const nlohmann::json json = readJsonFile(path.string());
  std::vector<TransformsFrame> frames;
  try {
    const auto& list = json.at("frames");
    if (!list.is_array() || list.empty())
      throwInputError("{}: \"frames\" must be a non-empty list", path.string());
    for (size_t f = 0; f < list.size(); ++f) {
      const auto& frame = list[f];
      const std::string where = fmt::format("{}: frames[{}]", path.string(), f);
      std::filesystem::path file = frame.at("file_path").get<std::string>();
      if (!file.has_extension()) file += ".png";
      const std::filesystem::path imagePath = (folder / file).lexically_normal();
      const glm::mat4 cameraToWorld =
          readCameraToWorld(frame.at("transform_matrix"), where + ".transform_matrix");
      bool hasAlpha = false;
      const ImageRgba8 image = readImage(imagePath, &hasAlpha);
      if (!hasAlpha)
        throwInputError(
            "{}: no alpha channel; a capture's images need alpha as the object's "
            "coverage (RGBA, background transparent)",
            imagePath.string());
      if (size == glm::ivec2(0)) size = {image.width, image.height};
      if (image.width != size.x || image.height != size.y) {
        throwInputError("{}: {}×{}, but the capture's images are {}×{}", imagePath.string(),
                        image.width, image.height, size.x, size.y);
      }
      frames.push_back({cameraToWorld,
                        readIntrinsics(json, frame, image.width, image.height, where),
                        toLinearPremultiplied(image), imagePath.string()});
    }
  } catch (const nlohmann::json::exception& e) {
    throwInputError("{}: {}", path.string(), e.what());
  }
  return frames;
}

// The frames as views of one centred camera (commonCentredPinhole), their images resampled to it
// where their own intrinsics differ.
std::vector<CapturedView> centredViews(std::vector<TransformsFrame>& frames,
                                       const CentredPinhole& camera) {
  std::vector<CapturedView> views;
  views.reserve(frames.size());
  const float angleX = float(2.0 * std::atan(0.5 * double(camera.width) / camera.focal));
  for (TransformsFrame& frame : frames) {
    views.push_back({cameraFromNerf(frame.cameraToWorld, angleX, camera.width, camera.height),
                     resampleToCentred(std::move(frame.image), frame.intrinsics, camera),
                     std::move(frame.name)});
  }
  return views;
}

// The point closest to every camera's optical axis (least squares): where the cameras look.
glm::vec3 commonFocus(const std::vector<CapturedView>& views) {
  glm::mat3 a(0.0f);
  glm::vec3 b(0.0f);
  for (const CapturedView& v : views) {
    const glm::vec3 d = glm::normalize(v.camera.target - v.camera.position);
    const glm::mat3 projector = glm::mat3(1.0f) - glm::outerProduct(d, d);
    a += projector;
    b += projector * v.camera.position;
  }
  if (std::abs(glm::determinant(a)) < 1e-6f) return views.front().camera.target;
  return glm::inverse(a) * b;
}

}  // namespace

Aabb visualHullBounds(const std::vector<CapturedView>& views, const Aabb& searchBox, int resolution,
                      float alphaThreshold) {
  std::vector<PixelCamera> cameras;
  std::vector<AlphaIntegral> masks;
  for (const CapturedView& v : views) {
    cameras.emplace_back(v.camera, v.image.width, v.image.height);
    masks.emplace_back(v.image, alphaThreshold);
  }
  const glm::vec3 cell = searchBox.extent() / float(resolution);
  Aabb hull;
  for (int z = 0; z < resolution; ++z) {
    for (int y = 0; y < resolution; ++y) {
      for (int x = 0; x < resolution; ++x) {
        Aabb box;
        box.min = searchBox.min + cell * glm::vec3(x, y, z);
        box.max = box.min + cell;
        bool carved = false;
        for (size_t v = 0; v < views.size() && !carved; ++v)
          carved = viewCarvesBox(cameras[v], masks[v], box);
        if (!carved) hull.extend(box);
      }
    }
  }
  return hull;
}

CaptureSet readNerfCaptures(const std::filesystem::path& folder) {
  if (!std::filesystem::is_directory(folder))
    throwInputError("{}: capture folder not found", folder.string());
  CaptureSet set;
  set.folder = folder;
  glm::ivec2 size(0);
  std::vector<TransformsFrame> train = readTransforms(folder, "transforms_train.json", size);
  std::vector<TransformsFrame> test = readTransforms(folder, "transforms_test.json", size);
  std::vector<PinholeIntrinsics> intrinsics;
  for (const auto* frames : {&train, &test})
    for (const TransformsFrame& frame : *frames) intrinsics.push_back(frame.intrinsics);
  const CentredPinhole camera = commonCentredPinhole(intrinsics);
  set.train = centredViews(train, camera);
  set.test = centredViews(test, camera);
  // Search where the cameras look, as far out as the nearest camera, then carve.
  const glm::vec3 focus = commonFocus(set.train);
  float reach = std::numeric_limits<float>::max();
  for (const CapturedView& v : set.train)
    reach = std::min(reach, glm::length(v.camera.position - focus));
  Aabb search;
  search.min = focus - glm::vec3(reach);
  search.max = focus + glm::vec3(reach);
  set.bounds = visualHullBounds(set.train, search);
  if (set.bounds.empty()) {
    throwInputError("{}: the training views' alpha masks have no common foreground",
                    folder.string());
  }
  // Near and far planes from the capture's extent.
  const float radius = 0.5f * glm::length(set.bounds.extent());
  for (auto* list : {&set.train, &set.test}) {
    for (CapturedView& v : *list) {
      const float distance = glm::length(v.camera.position - set.bounds.center());
      v.camera.nearPlane = std::max(0.01f * radius, distance - 1.5f * radius);
      v.camera.farPlane = distance + 1.5f * radius;
    }
  }
  return set;
}

}  // namespace canopy
