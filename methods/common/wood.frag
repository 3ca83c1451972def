#version 430 core
// Wood: base colour times optional texture, unlit albedo or Lambert.
in vec3 vNormal;
in vec2 vUv;

uniform sampler2D uWoodTexture;  // sRGB, so samples are linear
uniform int uHasTexture;
uniform vec3 uBaseColor;         // linear
#include "methods/common/lighting.glsl"
#include "methods/common/dither.glsl"

out vec4 outColor;

void main() {
  if (ditherRejects()) discard;
  vec3 color = uBaseColor;
  if (uHasTexture != 0) color *= texture(uWoodTexture, vUv).rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
    color *= lighting(normal, 1.0);
  }
  outColor = vec4(color, 1.0);
}
