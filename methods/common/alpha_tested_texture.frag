#version 430 core
// A textured billboard (the classic billboard cloud, the multi-layer method's far level): alpha
// test on the captured coverage (coverage_test.glsl), albedo or two-sided Lambert with the plane
// normal. Layer 0 holds what the billboard's front side sees, layer uBackLayer what its back side
// sees (the same plane points, so the same uv; 0 when only the front was captured).
in vec3 vNormal;
in vec2 vUv;

uniform sampler2DArray uAtlas;  // sRGB, so samples are linear
uniform float uBackLayer;
// 1 when the atlas is BC1: its transparent texels decode as black, which filtering blends into
// the edges of what passes the test; dividing by the filtered alpha gives back the covered
// texels' own colour (exact for BC1's 0-or-1 alpha).
uniform int uBinaryAlpha;
uniform sampler2D uOcclusion;  // ambient occlusion over the same atlas (R), when uHasOcclusion
uniform int uHasOcclusion;
// 1 when the atlas holds aggregate coverage (the indirect methods' low-resolution textures, a
// cell's leaves per texel), 0 when it holds leaf outlines (the classic cloud), 2 when it holds
// leaf outlines tested as aggregate coverage where minified (the classic cloud's hashed test).
uniform int uAggregateCoverage;
#include "methods/common/coverage_test.glsl"
#include "methods/common/lighting.glsl"

out vec4 outColor;

void main() {
  vec4 texel = texture(uAtlas, vec3(vUv, gl_FrontFacing ? 0.0 : uBackLayer));
  float threshold = uAggregateCoverage == 2
                        ? minifiedCoverageThreshold(textureQueryLod(uAtlas, vUv).y)
                        : coverageThreshold(uAggregateCoverage != 0);
  if (texel.a < threshold) discard;
  vec3 color = uBinaryAlpha != 0 ? texel.rgb / texel.a : texel.rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
#ifdef CANOPY_LIT
    color *= lighting(normal, uHasOcclusion != 0 ? texture(uOcclusion, vUv).r : 1.0);
#endif
  }
  outColor = vec4(color, 1.0);
}
