#version 430 core
// Alpha-tested texel of a box image (2D atlas) or of a polygonal leaf (front/back array), with
// an ordered-dither dissolve for blended transitions between levels and a second dither that
// blends a box's quads by facing (both order-independent: screen-door, no sorting).
in vec3 vNormal;
in vec2 vUv;
flat in vec2 vDissolve;
flat in vec2 vFacingRange;

uniform int uLeafMode;               // 0: box image from uAtlas; 1: leaf from uLeafImages
uniform sampler2D uAtlas;
uniform sampler2DArray uLeafImages;  // per leaf texture k: layer 2k front, 2k + 1 back
uniform int uTwoSided;               // 1 when back images differ from the front
// 1 when the atlas is BC1, whose transparent texels decode as black: dividing the filtered
// colour by the filtered alpha gives the covered texels' own colour.
uniform int uBinaryAlpha;
#include "methods/common/lighting.glsl"

out vec4 outColor;

float bayer4(ivec2 p) {
  const float m[16] = float[](0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5);
  return (m[(p.y & 3) * 4 + (p.x & 3)] + 0.5) / 16.0;
}

// A second dither, uncorrelated with bayer4 so a dissolving box still shows each quad its share
// (interleaved gradient noise: Jimenez 2014).
float gradientNoise(vec2 p) {
  return fract(52.9829189 * fract(dot(p, vec2(0.06711056, 0.00583715))));
}

void main() {
  float d = bayer4(ivec2(gl_FragCoord.xy));
  bool keepBelow = vDissolve.y > 0.5;
  if (keepBelow ? d >= vDissolve.x : d < vDissolve.x) discard;
  float facing = gradientNoise(floor(gl_FragCoord.xy));
  if (facing < vFacingRange.x || facing >= vFacingRange.y) discard;
  vec4 texel;
  if (uLeafMode == 0) {
    texel = texture(uAtlas, vUv);
  } else {
    // Leaf uv.x carries the texture index: uv.x = 2k + u, u in [0, 1].
    float k = floor(vUv.x * 0.5);
    vec2 uv = vec2(vUv.x - 2.0 * k, vUv.y);
    float layer = 2.0 * k + ((gl_FrontFacing || uTwoSided == 0) ? 0.0 : 1.0);
    texel = texture(uLeafImages, vec3(uv, layer));
  }
  if (texel.a < 0.5) discard;
  vec3 color = uLeafMode == 0 && uBinaryAlpha != 0 ? texel.rgb / texel.a : texel.rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
    color *= lighting(normal, 1.0);
  }
  outColor = vec4(color, 1.0);
}
