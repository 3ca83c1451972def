#include "common/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/error.h"
#include "common/file_checks.h"
#include "common/third_party_output.h"

namespace canopy {

namespace {

// The largest image Canopy decodes: a header may claim any size, and the pixels are allocated
// before a truncated file is noticed.
constexpr int kMaxImageSide = 16384;
constexpr int64_t kMaxImagePixels = int64_t(1) << 26;  // 8192², 256 MiB as RGBA8

// What went wrong, in one line: the library's own error, else what it printed.
std::string libraryMessage(const std::string& error, CapturedStderr& printed) {
  std::string message = asOneLine(error);
  return message.empty() ? printed.release() : message;
}

// Decodes the first subimage of an opened input into 8-bit RGBA; `name` appears in errors.
ImageRgba8 decodeImage(OIIO::ImageInput& input, const std::string& name, CapturedStderr& printed,
                       bool* hasAlpha = nullptr) {
  const OIIO::ImageSpec& spec = input.spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth != 1) {
    throwInputError("{}: unsupported image layout ({}x{}, {} channels)", name, spec.width,
                    spec.height, spec.nchannels);
  }
  if (spec.width > kMaxImageSide || spec.height > kMaxImageSide ||
      int64_t(spec.width) * spec.height > kMaxImagePixels) {
    throwInputError(
        "{}: {}×{} pixels is larger than Canopy reads (at most {} a side and {} "
        "pixels)",
        name, spec.width, spec.height, kMaxImageSide, kMaxImagePixels);
  }
  const int channels = spec.nchannels;
  std::vector<uint8_t> raw(size_t(spec.width) * spec.height * channels);
  if (!input.read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw.data())) {
    throwInputError("{}: truncated or corrupt image ({})", name,
                    libraryMessage(input.geterror(), printed));
  }
  ImageRgba8 image(spec.width, spec.height);
  const int alphaChannel = spec.alpha_channel >= 0 ? spec.alpha_channel : (channels == 4 ? 3 : -1);
  if (hasAlpha) *hasAlpha = alphaChannel >= 0 || channels == 2;
  for (size_t i = 0; i < size_t(spec.width) * spec.height; ++i) {
    const uint8_t* src = &raw[i * channels];
    uint8_t* dst = &image.pixels[i * 4];
    if (channels >= 3) {
      dst[0] = src[0];
      dst[1] = src[1];
      dst[2] = src[2];
    } else {
      dst[0] = dst[1] = dst[2] = src[0];
    }
    if (alphaChannel >= 0) {
      dst[3] = src[alphaChannel];
    } else if (channels == 2) {
      dst[3] = src[1];
    } else {
      dst[3] = 255;
    }
  }
  return image;
}

// The extension OpenImageIO picks its reader by: the hint, or what the first bytes say (models
// may leave the hint empty).
std::string formatOf(const void* data, size_t size, const std::string& hint) {
  if (!hint.empty()) return hint;
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (size >= 8 && std::memcmp(bytes, "\x89PNG\r\n\x1a\n", 8) == 0) return "png";
  if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return "jpg";
  return "png";  // the common case; a wrong guess reads as "not a readable image"
}

}  // namespace

ImageRgba8 readImage(const std::filesystem::path& path, bool* hasAlpha) {
  if (!regularFileExists(path)) {
    throwInputError("{}: image file does not exist", path.string());
  }
  // Leaf textures keep straight alpha: OIIO would otherwise premultiply PNG colour on read.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  CapturedStderr printed;  // libpng prints its errors itself; they belong in our message
  auto input = OIIO::ImageInput::open(path.string(), &config);
  if (!input) {
    throwInputError("{}: not a readable image ({})", path.string(),
                    libraryMessage(OIIO::geterror(), printed));
  }
  return decodeImage(*input, path.string(), printed, hasAlpha);
}

ImageRgba8 readImageFromMemory(const void* data, size_t size, const std::string& formatHint,
                               const std::string& name) {
  OIIO::Filesystem::IOMemReader reader(data, size);
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  // OpenImageIO 2.4's open() ignores its proxy argument (it then looks for a file named
  // "embedded.png"); the proxy handed over in the config is honoured.
  void* proxy = &reader;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  CapturedStderr printed;
  auto input = OIIO::ImageInput::open("embedded." + formatOf(data, size, formatHint), &config);
  if (!input)
    throwInputError("{}: not a readable image ({})", name,
                    libraryMessage(OIIO::geterror(), printed));
  return decodeImage(*input, name, printed);
}

void writePng(const std::filesystem::path& path, const ImageRgba8& image) {
  assert(!image.empty());
  writeFileAtomically(path, [&](const std::filesystem::path& temporary) {
    auto output = OIIO::ImageOutput::create("png");
    if (!output) throw std::runtime_error("OpenImageIO has no PNG writer");
    OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:ColorSpace", "sRGB");
    spec.attribute("oiio:UnassociatedAlpha", 1);  // our pixels are straight alpha: store as is
    if (!output->open(temporary.string(), spec) ||
        !output->write_image(OIIO::TypeDesc::UINT8, image.pixels.data()) || !output->close()) {
      throwInputError("{}: cannot write PNG ({})", path.string(), asOneLine(output->geterror()));
    }
  });
}

ImageRgbaF boxDownsample(const ImageRgbaF& image, int factor) {
  assert(factor >= 1 && image.width % factor == 0 && image.height % factor == 0);
  if (factor == 1) return image;
  ImageRgbaF result(image.width / factor, image.height / factor);
  const float weight = 1.0f / float(factor * factor);
  for (int y = 0; y < result.height; ++y) {
    for (int x = 0; x < result.width; ++x) {
      float sum[4] = {0, 0, 0, 0};
      for (int sy = 0; sy < factor; ++sy) {
        for (int sx = 0; sx < factor; ++sx) {
          const float* p = image.at(x * factor + sx, y * factor + sy);
          for (int c = 0; c < 4; ++c) sum[c] += p[c];
        }
      }
      float* out = result.at(x, y);
      for (int c = 0; c < 4; ++c) out[c] = sum[c] * weight;
    }
  }
  return result;
}

float srgbToLinear(float value) {
  return value <= 0.04045f ? value / 12.92f : std::pow((value + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float value) {
  value = std::clamp(value, 0.0f, 1.0f);
  return value <= 0.0031308f ? value * 12.92f : 1.055f * std::pow(value, 1.0f / 2.4f) - 0.055f;
}

uint8_t encodeSrgb8(float linear) {
  return static_cast<uint8_t>(std::lround(linearToSrgb(linear) * 255.0f));
}

ImageRgba8 compositeToSrgb8(const ImageRgbaF& image, glm::vec3 backgroundLinear) {
  ImageRgba8 result(image.width, image.height);
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i) {
    const float* p = &image.pixels[i * 4];
    const float alpha = std::clamp(p[3], 0.0f, 1.0f);
    uint8_t* out = &result.pixels[i * 4];
    for (int c = 0; c < 3; ++c) out[c] = encodeSrgb8(p[c] + (1.0f - alpha) * backgroundLinear[c]);
    out[3] = static_cast<uint8_t>(std::lround(alpha * 255.0f));
  }
  return result;
}

ImageRgba8 withOpaqueAlpha(ImageRgba8 image) {
  for (size_t i = 3; i < image.pixels.size(); i += 4) image.pixels[i] = 255;
  return image;
}

void flipRows(ImageRgbaF& image) {
  const size_t rowFloats = size_t(image.width) * 4;
  for (int y = 0; y < image.height / 2; ++y) {
    std::swap_ranges(image.pixels.begin() + y * rowFloats,
                     image.pixels.begin() + (y + 1) * rowFloats,
                     image.pixels.begin() + (image.height - 1 - y) * rowFloats);
  }
}

}  // namespace canopy
