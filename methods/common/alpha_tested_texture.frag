#version 430 core
// A textured billboard (the classic billboard cloud, the multi-layer method's far level): alpha
// test at 0.5 on the captured coverage, albedo or two-sided Lambert with the plane normal.
in vec3 vNormal;
in vec2 vUv;

uniform sampler2D uAtlas;  // sRGB, so samples are linear
uniform sampler2D uOcclusion;  // ambient occlusion over the same atlas (R), when uHasOcclusion
uniform int uHasOcclusion;
#include "methods/common/lighting.glsl"

out vec4 outColor;

void main() {
  vec4 texel = texture(uAtlas, vUv);
  if (texel.a < 0.5) discard;
  vec3 color = texel.rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
#ifdef CANOPY_LIT
    color *= lighting(normal, uHasOcclusion != 0 ? texture(uOcclusion, vUv).r : 1.0);
#endif
  }
  outColor = vec4(color, 1.0);
}
