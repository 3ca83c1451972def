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

uniform sampler2D uColor;     // sRGB colour, alpha coverage
uniform sampler2D uDepth;     // R: depth along each frame's view in the sphere, 0 near ... 1 far
uniform sampler2D uNormals;   // RGB normal · 0.5 + 0.5 (tree space), at the depth's resolution
uniform float uDepthLodOffset;  // log2 of the colour atlas's size over the depth atlas's
uniform mat4 uViewProjection;
uniform int uOrthographic;
uniform vec3 uCenter;
uniform float uRadius;
uniform float uInnerUv;       // one frame image's side in atlas uv
// BLEND_FRAMES (1 or 3) and PARALLAX_STEPS are compile-time constants (octahedral.cpp defines
// them), so the loops unroll: a CPU rasteriser pays for every masked loop iteration.
#include "methods/common/lighting.glsl"
#include "methods/common/dither.glsl"

out vec4 outColor;

struct Blend {
  vec4 sum;       // premultiplied colour and weight × coverage
  vec3 point;     // surface points weighted alike
  vec3 normal;
};

// Frame k's image seen along `ray`: a few fixed-point steps move the lookup from the quad point
// to where the ray meets the surface that frame's depth holds.
void addFrame(vec3 right, vec3 up, vec3 toCamera, vec2 origin, float weight, vec3 ray,
              float lod, float depthLod, inout Blend blend) {
  vec3 p = vLocalPosition;
  float along = max(dot(ray, -toCamera), 0.2);
  for (int step = 0; step < PARALLAX_STEPS; ++step) {
    vec2 s = vec2(dot(p - uCenter, right), dot(p - uCenter, up)) / uRadius;
    float surface = (textureLod(uDepth, origin + (s * 0.5 + 0.5) * uInnerUv, depthLod).r * 2.0 -
                     1.0) * uRadius;
    p += ray * ((surface - dot(p - uCenter, -toCamera)) / along);
  }
  vec2 s = vec2(dot(p - uCenter, right), dot(p - uCenter, up)) / uRadius;
  vec2 uv = origin + (s * 0.5 + 0.5) * uInnerUv;
  vec4 texel = textureLod(uColor, uv, lod);
  float a = weight * texel.a;
  blend.sum += vec4(texel.rgb * a, a);
  blend.point += p * a;
#ifdef CANOPY_LIT
  blend.normal += (textureLod(uNormals, uv, depthLod).rgb * 2.0 - 1.0) * a;
#endif
}

void main() {
  if (ditherRejects()) discard;
  vec3 ray = uOrthographic != 0 ? vForwardLocal : normalize(vLocalPosition - vEyeLocal);
  float depthLod = max(vLod - uDepthLodOffset, 0.0);
  Blend blend = Blend(vec4(0.0), vec3(0.0), vec3(0.0));
  addFrame(vRight[0], vUp[0], vToCamera[0], vOrigin[0], vWeights[0], ray, vLod, depthLod, blend);
#if BLEND_FRAMES == 3
  addFrame(vRight[1], vUp[1], vToCamera[1], vOrigin[1], vWeights[1], ray, vLod, depthLod, blend);
  addFrame(vRight[2], vUp[2], vToCamera[2], vOrigin[2], vWeights[2], ray, vLod, depthLod, blend);
#endif
  if (blend.sum.a < 0.5) discard;
  vec4 world = vModel * vec4(blend.point / blend.sum.a, 1.0);
  vec4 clip = uViewProjection * world;
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
  vec3 color = blend.sum.rgb / blend.sum.a;
#ifdef CANOPY_LIT
  vec3 normal = normalize(mat3(vModel) * blend.normal);
  color *= lightingAt(world.xyz, normal, 1.0);
#endif
  outColor = vec4(color, 1.0);
}
