#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace canopy {

// 8-bit RGBA image, rows top to bottom, straight (not premultiplied) alpha, colour in sRGB.
struct ImageRgba8 {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // width * height * 4

  ImageRgba8() = default;
  ImageRgba8(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h) * 4, 0) {}
  bool empty() const { return width == 0 || height == 0; }
  uint8_t* at(int x, int y) { return &pixels[(size_t(y) * width + x) * 4]; }
  const uint8_t* at(int x, int y) const { return &pixels[(size_t(y) * width + x) * 4]; }
  bool operator==(const ImageRgba8&) const = default;
};

// Float RGBA image, rows top to bottom, linear colour, premultiplied alpha: the form rendered
// images take between read-back and scoring, because box filtering is exact only on it.
struct ImageRgbaF {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;  // width * height * 4

  ImageRgbaF() = default;
  ImageRgbaF(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h) * 4, 0.0f) {}
  float* at(int x, int y) { return &pixels[(size_t(y) * width + x) * 4]; }
  const float* at(int x, int y) const { return &pixels[(size_t(y) * width + x) * 4]; }
};

// Reads any image OpenImageIO can read into 8-bit RGBA (grey → RGB, no alpha → opaque).
// Throws InputError naming the file when it is missing, not an image or larger than 8192² pixels;
// what the image library prints on its own is folded into that message. `hasAlpha`, when given,
// says whether the file had an alpha channel.
ImageRgba8 readImage(const std::filesystem::path& path, bool* hasAlpha = nullptr);
// The same for an image held in memory (e.g. embedded in a GLB); `formatHint` is an extension
// such as "png", `name` what errors call it.
ImageRgba8 readImageFromMemory(const void* data, size_t size, const std::string& formatHint,
                               const std::string& name);

// Writes a PNG atomically (temporary file, then rename). Throws std::runtime_error on failure.
void writePng(const std::filesystem::path& path, const ImageRgba8& image);

// Averages factor × factor blocks: the box filter from the supersampled render to the
// evaluation resolution. Width and height must be multiples of factor.
ImageRgbaF boxDownsample(const ImageRgbaF& image, int factor);

// sRGB transfer functions on [0, 1].
float srgbToLinear(float value);
float linearToSrgb(float value);
uint8_t encodeSrgb8(float linear);

// Composites a premultiplied linear image over an opaque background colour (linear) and encodes
// it to 8-bit sRGB; alpha of the result keeps the coverage (0..255).
ImageRgba8 compositeToSrgb8(const ImageRgbaF& image, glm::vec3 backgroundLinear);

// A copy with alpha 255 everywhere: what a person sees of a composited image.
ImageRgba8 withOpaqueAlpha(ImageRgba8 image);

// Flips rows (GL read-back is bottom-up).
void flipRows(ImageRgbaF& image);

}  // namespace canopy
