#pragma once

#include <filesystem>
#include <vector>

#include "common/image.h"
#include "common/tree.h"
#include "common/views.h"

namespace canopy {

// One calibrated photograph: the camera that took it and the image, linear premultiplied RGBA
// with alpha the pixel's coverage (the form Harness::renderLinear produces).
struct CapturedView {
  Camera camera;
  ImageRgbaF image;
  std::string name;  // file it came from, or "view <i>" for rendered photographs
};

// A multi-view capture: views a method may reconstruct from (train) and held-out views it is
// scored on (test), both in the capture's world frame.
struct CaptureSet {
  std::filesystem::path folder;
  std::vector<CapturedView> train;
  std::vector<CapturedView> test;
  Aabb bounds;  // the visual hull of the train views' alpha masks
};

// A camera with its image size: world ↔ pixel. Pixel coordinates run from the top-left corner
// of the image (x right, y down), pixel centres at +0.5.
class PixelCamera {
 public:
  PixelCamera(const Camera& camera, int width, int height);
  int width() const { return mWidth; }
  int height() const { return mHeight; }
  float focalPixels() const { return mFocal; }  // focal length in pixels
  const glm::vec3& position() const { return mPosition; }
  const glm::vec3& forward() const { return mForward; }  // unit viewing direction
  const glm::vec3& right() const { return mRight; }      // unit, image x
  const glm::vec3& up() const { return mUp; }            // unit, image −y
  // Depth along the viewing direction (negative behind the camera).
  float depth(const glm::vec3& point) const { return glm::dot(point - mPosition, mForward); }
  // Pixel coordinates of a point with depth > 0.
  glm::vec2 project(const glm::vec3& point) const;
  // Unit direction of the ray through pixel coordinates `pixel`.
  glm::vec3 rayDirection(glm::vec2 pixel) const;

 private:
  int mWidth, mHeight;
  float mFocal;
  glm::vec3 mPosition, mForward, mRight, mUp;
};

// Sums over rectangles of an image's alpha in O(1): the average alpha in a cell's projection
// (§5's initialisation) and whether any pixel there is foreground (the visual hull).
class AlphaIntegral {
 public:
  AlphaIntegral(const ImageRgbaF& image, float foregroundAlpha);
  // Pixels [x0, x1) × [y0, y1), clamped to the image.
  double alphaSum(int x0, int y0, int x1, int y1) const;
  uint32_t foregroundCount(int x0, int y0, int x1, int y1) const;

 private:
  int mWidth, mHeight;
  std::vector<double> mAlpha;  // (w+1)·(h+1) prefix sums
  std::vector<uint32_t> mForeground;
};

// Where a box falls in an image: its projected bounding rectangle in whole pixels, or nothing
// when a corner is behind the camera or the rectangle leaves the image (the view then says
// nothing certain about the box).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  int area() const { return (x1 - x0) * (y1 - y0); }
};
bool projectBoxInside(const PixelCamera& camera, const Aabb& box, PixelRect& rect);

// Whether one view proves a box empty: its projection lies wholly inside the image on pixels with
// no foreground, or wholly outside the image (a capture shows the whole object in every view).
bool viewCarvesBox(const PixelCamera& camera, const AlphaIntegral& mask, const Aabb& box);

// Reads a folder in the NeRF synthetic layout: transforms_train.json and transforms_test.json,
// each {"camera_angle_x": radians, "frames": [{"file_path": "./train/r_0", "transform_matrix":
// 4×4 camera-to-world, camera looking down −Z}]}; images are RGBA PNGs (".png" is appended when
// file_path has no extension). The intrinsics nerfstudio and instant-ngp write (fl_x, fl_y, cx,
// cy, w, h, at the top level or per frame; capture_intrinsics.h) are read too: frames whose
// principal point is off centre or whose pixels are not square are resampled to one centred
// square-pixel camera that holds every frame's view. Throws InputError naming the file for
// malformed JSON, missing keys, bad intrinsics, missing images, images without alpha, images
// whose size differs from the first one's, and matrices that are no camera pose.
CaptureSet readNerfCaptures(const std::filesystem::path& folder);

// The camera of a NeRF frame: `cameraToWorld` column-major (glm) as in transform_matrix,
// horizontal field of view in radians, image size.
Camera cameraFromNerf(const glm::mat4& cameraToWorld, float cameraAngleX, int width, int height);

// The bounding box of the points every view sees with alpha > `alphaThreshold` (or does not see
// at all), found by carving a `resolution`³ grid inside `searchBox`; empty when nothing survives.
Aabb visualHullBounds(const std::vector<CapturedView>& views, const Aabb& searchBox,
                      int resolution = 64, float alphaThreshold = 0.02f);

// Straight sRGB 8-bit image → linear premultiplied float image, and back.
ImageRgbaF toLinearPremultiplied(const ImageRgba8& image);
ImageRgba8 toStraightSrgb8(const ImageRgbaF& image);

// Writes views as a NeRF-layout folder: <split>/r_<i>.png and transforms_<split>.json for the
// splits "train" and "test" (the inverse of readNerfCaptures). All views share one horizontal
// field of view and size.
void writeNerfCaptures(const std::filesystem::path& folder, const std::vector<CapturedView>& train,
                       const std::vector<CapturedView>& test);

}  // namespace canopy
