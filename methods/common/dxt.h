#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/gl/device.h"
#include "common/image.h"

namespace canopy {

// S3TC block compression of colour textures (the multi-layer paper's Table 1 uses DXT).
enum class Compression {
  kNone,
  kDxt1,  // BC1, 4 bits per texel: RGB + 1-bit alpha (alpha >= 128 opaque), 8:1 against RGBA8
  kDxt5,  // BC3, 8 bits per texel: BC1 colour + interpolated 8-bit alpha, 4:1
};
Compression parseCompression(const std::string& name);  // "none" | "dxt1" | "dxt5"

// Blocks of one image (4×4 texels each, rows of blocks top to bottom), sRGB values encoded as is.
std::vector<uint8_t> compressImage(const ImageRgba8& image, Compression compression);

// True when the current context can sample S3TC (GL_EXT_texture_compression_s3tc).
bool driverHasS3tc();
// Bad input (InputError naming the parameter) when `compression` needs S3TC and the current
// context has none: every upload of a compressed texture checks through it.
void requireS3tcFor(Compression compression);

// The GL internal format of sRGB colour in the given compression (GL_SRGB8_ALPHA8 for kNone).
GLenum srgbInternalFormat(Compression compression);

}  // namespace canopy
