#version 430 core
// Multi-layer indirect texturing, single pass (García et al. 2007 §5, Fig. 7): the hash cell
// names a list of leaf fragments; walk it from the end facing the viewer until an opaque leaf
// texel; evaluate at most a number of entries that falls with the projected size of a hash texel
// (§5.1) and take the missing leaves from one fetch of the low-resolution texture.
// A list entry names a leaf record: the leaf's centre, height and frame in the billboard's frame.
// The fragment's plane point is mapped into the leaf's own (s, t) through that frame, so a leaf
// shows its true outline and the side it turns to the viewer. With PARALLAX the point is first
// moved along the view ray to the leaf's plane (exact ray–leaf intersection), and the fragment
// takes the depth of the leaf point it shows.
// Defined before this line by the method: RECORDS_8BIT (0/1), PARALLAX (0/1).
in vec3 vNormal;
in vec2 vUv;
in vec2 vLowResUv;
flat in ivec4 vHash;
flat in vec2 vHalfExtents;
flat in vec3 vTangent;
flat in int vRecordBase;
flat in float vScale;

uniform usampler2D uHash;        // R32UI: (list start << 8) | list length, 0 when empty
uniform usampler2D uLists;       // R16UI/R32UI: record index relative to the billboard's first
uniform sampler2D uRecords;      // three texels a record (list_textures.h)
uniform sampler2DArray uLeaves;  // leaf images, sRGB: image i front at 2i, back at 2i + 1
uniform sampler2DArray uLowRes;  // the layered representation at low resolution: front, back
uniform sampler2D uAmbientOcclusion;  // per record: ambient term at the leaf's four corners
uniform float uLodFactor;        // entries = factor × projected hash-texel diagonal (px); 0: all
uniform float uTargetPixelsPerOutputPixel;  // supersampling: derivatives count target pixels
uniform vec3 uCameraPosition;
uniform mat4 uViewProjection;
uniform float uAxisScale;    // 8-bit records: range of the frame components
uniform float uHeightScale;  // 8-bit records: range of the heights
uniform float uMaxSlope;     // parallax: steeper rays are bent to this in-plane slope
uniform int uBinaryAlpha;    // BC1 images: divide the filtered colour by the filtered alpha
#include "methods/common/lighting.glsl"
#ifndef CANOPY_LIT
in vec3 vWorldPosition;  // lighting.glsl declares it for lit frames
#endif
uniform sampler2D uLowResOcclusion;  // AO over the low-resolution atlas (R)
uniform int uHasLowResOcclusion;

out vec4 outColor;

const int kRecordsPerRow = 1024;
const int kListsWidth = 4096;

struct Record {
  vec2 center;
  float height;
  vec3 axisU;  // the leaf's axes times its half extents, in the billboard frame
  vec3 axisV;
  float image;
};

Record fetchRecord(int r) {
  ivec2 at = ivec2(3 * (r % kRecordsPerRow), r / kRecordsPerRow);
  vec4 t0 = texelFetch(uRecords, at, 0);
  vec4 t1 = texelFetch(uRecords, at + ivec2(1, 0), 0);
  vec4 t2 = texelFetch(uRecords, at + ivec2(2, 0), 0);
  Record record;
#if RECORDS_8BIT
  vec2 words = vec2(t0.x * 65280.0 + t0.y * 255.0, t0.z * 65280.0 + t0.w * 255.0);
  record.center = (words / 65535.0 * 2.0 - 1.0) * vHalfExtents;
  vec4 s1 = (t1 * 255.0 - 128.0) / 127.0;
  vec3 s2 = (t2.xyz * 255.0 - 128.0) / 127.0;
  record.axisU = vec3(s1.xy, s2.y) * uAxisScale;
  record.axisV = vec3(s1.zw, s2.z) * uAxisScale;
  record.height = s2.x * uHeightScale;
  record.image = floor(t2.w * 255.0 + 0.5);
#else
  record.center = t0.xy;
  record.height = t0.z;
  record.image = floor(t0.w + 0.5);
  record.axisU = vec3(t1.xy, t2.x);
  record.axisV = vec3(t1.zw, t2.y);
#endif
  return record;
}

vec3 shade(vec3 albedo, float occlusion, vec3 normal) { return albedo * lighting(normal, occlusion); }

void main() {
  vec2 grid = vUv * vec2(vHash.zw);
  vec2 plane = (vUv * 2.0 - 1.0) * vHalfExtents;
  vec2 planeDx = dFdx(plane), planeDy = dFdy(plane);
  float pixelsPerCell = 1.0 / max(max(length(dFdx(grid)), length(dFdy(grid))), 1e-6) /
                        uTargetPixelsPerOutputPixel;  // output pixels, as every LoD decision
  ivec2 cell = clamp(ivec2(floor(grid)), ivec2(0), vHash.zw - 1);
  uint cellWord = texelFetch(uHash, vHash.xy + cell, 0).r;
  if (cellWord == 0u) discard;
  int start = int(cellWord >> 8u);
  int listLength = int(cellWord & 255u);
  int budget = listLength;
  if (uLodFactor > 0.0)
    budget = min(listLength, int(ceil(uLodFactor * 1.41421356 * pixelsPerCell)));

  // The billboard frame in world space and the direction towards the viewer in it.
  vec3 n = normalize(vNormal);
  vec3 t = normalize(vTangent - dot(vTangent, n) * n);
  vec3 b = cross(n, t);
  vec3 toViewer = uCameraPosition - vWorldPosition;
  vec3 viewer = vec3(dot(toViewer, t), dot(toViewer, b), dot(toViewer, n));
  bool fromFront = viewer.z > 0.0;
  vec2 slope = vec2(0.0);
#if PARALLAX
  // A point at height z along the ray through this fragment lies at plane point plane + z·slope.
  slope = clamp(viewer.xy / (fromFront ? max(viewer.z, 1e-6) : min(viewer.z, -1e-6)),
                -uMaxSlope, uMaxSlope);
#endif
  for (int i = 0; i < budget; ++i) {
    int k = start + (fromFront ? i : listLength - 1 - i);
    int r = vRecordBase + int(texelFetch(uLists, ivec2(k % kListsWidth, k / kListsWidth), 0).r);
    Record record = fetchRecord(r);
    // Solve centre + s·a + t·b = plane + (height + s·axisU.z + t·axisV.z)·slope for (s, t).
    vec2 a = record.axisU.xy - record.axisU.z * slope;
    vec2 c = record.axisV.xy - record.axisV.z * slope;
    float det = a.x * c.y - a.y * c.x;
    if (abs(det) < 1e-12) continue;  // the ray runs along the leaf
    mat2 inverse = mat2(c.y, -a.y, -c.x, a.x) / det;
    vec2 st = inverse * (plane - record.center + record.height * slope);
    if (any(greaterThan(abs(st), vec2(1.0)))) continue;
    vec3 leafNormal = cross(record.axisU, record.axisV);  // the front, as the reference winds it
    bool front = dot(leafNormal, viewer) > 0.0;
    vec2 uv = st * 0.5 + 0.5;
    vec4 texel = textureGrad(uLeaves, vec3(uv, 2.0 * record.image + (front ? 0.0 : 1.0)),
                             0.5 * (inverse * planeDx), 0.5 * (inverse * planeDy));
    if (texel.a < 0.5) continue;
    if (uBinaryAlpha != 0) texel.rgb /= texel.a;  // BC1's transparent texels are black
#if PARALLAX
    float z = record.height + st.x * record.axisU.z + st.y * record.axisV.z;
    vec4 clip = uViewProjection *
                vec4(vWorldPosition + vScale * z * (n + slope.x * t + slope.y * b), 1.0);
    gl_FragDepth = clip.z / clip.w * 0.5 + 0.5;
#endif
#ifdef CANOPY_LIT
    vec4 corners = texelFetch(uAmbientOcclusion, ivec2(r % kRecordsPerRow, r / kRecordsPerRow), 0);
    float occlusion = mix(mix(corners.x, corners.y, uv.x), mix(corners.w, corners.z, uv.x), uv.y);
    vec3 world = leafNormal.x * t + leafNormal.y * b + leafNormal.z * n;
    outColor = vec4(shade(texel.rgb, occlusion, normalize(front ? world : -world)), 1.0);
#else
    outColor = vec4(texel.rgb, 1.0);  // unlit: albedo (lit-only work is compiled out)
#endif
    return;
  }
  if (budget < listLength) {
    vec4 texel = texture(uLowRes, vec3(vLowResUv, fromFront ? 0.0 : 1.0));
    if (texel.a >= 0.5) {
      if (uBinaryAlpha != 0) texel.rgb /= texel.a;
#if PARALLAX
      gl_FragDepth = gl_FragCoord.z;
#endif
#ifdef CANOPY_LIT
      float occlusion = uHasLowResOcclusion != 0 ? texture(uLowResOcclusion, vLowResUv).r : 1.0;
      outColor = vec4(shade(texel.rgb, occlusion, fromFront ? n : -n), 1.0);
#else
      outColor = vec4(texel.rgb, 1.0);
#endif
      return;
    }
  }
  discard;
}
