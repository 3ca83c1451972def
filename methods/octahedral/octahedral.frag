#version 430 core
// An octahedral impostor's fragment: each of the instance's frames is looked up where the view
// ray meets the surface that frame saw (a few fixed-point steps on its depth map), the frames
// blended by weight (premultiplied), alpha-tested at 0.5 on the captured coverage; the depth of
// the blended surface point is written, so impostors intersect each other and the shadow map
// holds the tree's own depth.
flat in vec3 vRight[3];
flat in vec3 vUp[3];
flat in vec3 vToCamera[3];
flat in vec2 vOrigin[3];
flat in vec3 vWeights;
flat in mat4 vModel;
flat in vec3 vEyeLocal;
flat in vec3 vForwardLocal;
flat in float vLod;
in vec3 vLocalPosition;

uniform sampler2D uColor;        // sRGB colour, alpha coverage
uniform sampler2D uNormalDepth;  // RGB normal · 0.5 + 0.5 (tree space), A depth in the sphere
uniform float uNormalDepthLodOffset;  // log2 of the colour atlas's size over the normal-depth's
uniform mat4 uViewProjection;
uniform int uOrthographic;
uniform vec3 uCenter;
uniform float uRadius;
uniform float uInnerUv;          // one frame image's side in atlas uv
uniform int uParallaxSteps;      // 0: each frame looked up at the quad point itself
uniform int uBlendFrames;
#include "methods/common/lighting.glsl"
#include "methods/common/dither.glsl"

out vec4 outColor;

vec2 frameUv(int k, vec3 p) {
  vec2 s = vec2(dot(p - uCenter, vRight[k]), dot(p - uCenter, vUp[k])) / uRadius;
  return vOrigin[k] + (s * 0.5 + 0.5) * uInnerUv;
}

void main() {
  if (ditherRejects()) discard;
  vec3 ray = uOrthographic != 0 ? vForwardLocal : normalize(vLocalPosition - vEyeLocal);
  float depthLod = max(vLod - uNormalDepthLodOffset, 0.0);
  vec4 sum = vec4(0.0);
  vec3 pointSum = vec3(0.0);
  vec3 normalSum = vec3(0.0);
  for (int k = 0; k < uBlendFrames; ++k) {
    float weight = vWeights[k];
    if (weight <= 0.0) continue;
    vec3 p = vLocalPosition;
    float along = max(dot(ray, -vToCamera[k]), 0.2);
    for (int step = 0; step < uParallaxSteps; ++step) {
      float surface = (textureLod(uNormalDepth, frameUv(k, p), depthLod).a * 2.0 - 1.0) * uRadius;
      p += ray * ((surface - dot(p - uCenter, -vToCamera[k])) / along);
    }
    vec2 uv = frameUv(k, p);
    vec4 texel = textureLod(uColor, uv, vLod);
    float a = weight * texel.a;
    sum += vec4(texel.rgb * a, a);
    pointSum += p * a;
#ifdef CANOPY_LIT
    normalSum += (textureLod(uNormalDepth, uv, depthLod).rgb * 2.0 - 1.0) * a;
#endif
  }
  if (sum.a < 0.5) discard;
  vec4 world = vModel * vec4(pointSum / sum.a, 1.0);
  vec4 clip = uViewProjection * world;
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  vec3 color = sum.rgb / sum.a;
#ifdef CANOPY_LIT
  vec3 normal = normalize(mat3(vModel) * normalSum);
  color *= lightingAt(world.xyz, normal, 1.0);
#endif
  outColor = vec4(color, 1.0);
}
