#version 450 core
// The textures of the two closest input cameras, weighted by angle, premultiplied for the over
// operator (§6). Texels are bytes in storage buffers: alpha per texture, sRGB per packed slot.
layout(std430, binding = 3) readonly buffer SlotOfTile { uint slotOf[]; };
layout(std430, binding = 4) readonly buffer AlphaBytes { uint alphaWords[]; };
layout(std430, binding = 5) readonly buffer RgbBytes { uint rgbWords[]; };

uniform int uTexels;
uniform float uWeight0;
uniform float uWeight1;

flat in uint vTile0;
flat in uint vTile1;
in vec2 vTexel;
out vec4 fragColor;

const uint kNoTile = 0xffffffffu;

uint alphaByte(uint i) { return (alphaWords[i >> 2] >> ((i & 3u) * 8u)) & 255u; }
uint rgbByte(uint i) { return (rgbWords[i >> 2] >> ((i & 3u) * 8u)) & 255u; }

float srgbToLinear(float c) {
  return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

vec4 texelOf(uint tile, uint texel) {
  if (tile == kNoTile) return vec4(0.0);
  uint texels = uint(uTexels * uTexels);
  float alpha = float(alphaByte(tile * texels + texel)) / 255.0;
  if (alpha <= 0.0) return vec4(0.0);
  uint base = (slotOf[tile] * texels + texel) * 3u;
  vec3 rgb = vec3(srgbToLinear(float(rgbByte(base)) / 255.0),
                  srgbToLinear(float(rgbByte(base + 1u)) / 255.0),
                  srgbToLinear(float(rgbByte(base + 2u)) / 255.0));
  return vec4(rgb * alpha, alpha);
}

void main() {
  ivec2 t = clamp(ivec2(floor(vTexel)), ivec2(0), ivec2(uTexels - 1));
  uint texel = uint(t.y * uTexels + t.x);
  vec4 color = uWeight0 * texelOf(vTile0, texel) + uWeight1 * texelOf(vTile1, texel);
  if (color.a < 1.0 / 1024.0) discard;
  fragColor = color;
}
