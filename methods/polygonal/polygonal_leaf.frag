#version 430 core
// Leaves: front or back image by facing, alpha test at 0.5, unlit albedo or two-sided Lambert.
in vec3 vNormal;
in vec2 vUv;
in float vOcclusion;  // baked AO of lit runs, 1 otherwise

uniform sampler2DArray uLeafImages;  // layer 0 front, uBackLayer back; sRGB, so samples are linear
uniform float uBackLayer;            // 1 for two-sided images, 0 when the back is the front
#include "methods/common/lighting.glsl"
#include "methods/common/dither.glsl"

out vec4 outColor;

void main() {
  if (ditherRejects()) discard;
  vec4 texel = texture(uLeafImages, vec3(vUv, gl_FrontFacing ? 0.0 : uBackLayer));
  if (texel.a < 0.5) discard;
  vec3 color = texel.rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
    color *= lighting(normal, vOcclusion);
  }
  outColor = vec4(color, 1.0);  // premultiplied: opaque after the alpha test
}
