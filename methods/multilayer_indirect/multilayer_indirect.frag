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
#if RECORDS_8BIT
uniform usampler2D uRecordsA;    // RGBA16UI: centre, axisU.xy, axisV.xy (list_textures.h)
uniform sampler2D uRecordsB;     // RGBA8: height, axisU.z, axisV.z, image
#else
uniform sampler2D uRecordsA;     // RGBA16F: centre, axisU.xy
uniform sampler2D uRecordsB;     // RGBA16F: axisV.xy, height, image
uniform sampler2D uRecordsC;     // RG16F: axisU.z, axisV.z
#endif
uniform sampler2DArray uLeaves;  // leaf images, sRGB: image i front at 2i, back at 2i + 1
uniform sampler2DArray uLowRes;  // the layered representation at low resolution: front, back
uniform sampler2D uAmbientOcclusion;  // per record: ambient term at the leaf's four corners
uniform float uLodFactor;        // entries = factor × projected hash-texel diagonal (px); 0: all
uniform int uLowResRestOnly;     // lowres_fallback "rest": the texel covers the unwalked leaves
uniform float uTargetPixelsPerOutputPixel;  // supersampling: derivatives count target pixels
uniform vec3 uCameraPosition;
uniform mat4 uViewProjection;
uniform float uAxisScale;    // 8-bit records: range of the frame components
uniform float uHeightScale;  // 8-bit records: range of the heights
uniform float uMaxSlope;     // parallax: steeper rays are bent to this in-plane slope
// BC1 images: divide the filtered colour by the filtered alpha (transparent texels are black).
uniform int uLeavesBinaryAlpha;
uniform int uLowResBinaryAlpha;
#include "methods/common/coverage_test.glsl"
#include "methods/common/lighting.glsl"
#ifndef CANOPY_LIT
in vec3 vWorldPosition;  // lighting.glsl declares it for lit frames
#endif
uniform sampler2D uLowResOcclusion;  // AO over the low-resolution atlas (R)
uniform int uHasLowResOcclusion;

out vec4 outColor;

const int kRecordsPerRow = 1024;
const int kListsWidth = 4096;

// A leaf record (list_textures.h), fetched in two steps: what locating the fragment's point on
// the leaf needs, then, for the entry it hits, the rest.
struct Record {
  vec2 center;
  vec3 axisU;  // the leaf's axes times its half extents, in the billboard frame
  vec3 axisV;
  float height;
  float image;
};

float signedByte(float unit) { return (unit * 255.0 - 128.0) / 127.0; }

// Centre and in-plane axes (and, for parallax, everything).
Record fetchPlanar(ivec2 at) {
  Record record;
#if RECORDS_8BIT
  uvec4 a = texelFetch(uRecordsA, at, 0);
  record.center = (vec2(a.xy) / 65535.0 * 2.0 - 1.0) * vHalfExtents;
  record.axisU = vec3((vec2(a.z >> 8u, a.z & 255u) - 128.0) / 127.0 * uAxisScale, 0.0);
  record.axisV = vec3((vec2(a.w >> 8u, a.w & 255u) - 128.0) / 127.0 * uAxisScale, 0.0);
  record.height = 0.0;  // completeRecord fills these
  record.image = 0.0;
#else
  vec4 a = texelFetch(uRecordsA, at, 0);
  vec4 b = texelFetch(uRecordsB, at, 0);
  record.center = a.xy;
  record.axisU = vec3(a.zw, 0.0);
  record.axisV = vec3(b.xy, 0.0);
  record.height = b.z;
  record.image = floor(b.w + 0.5);
#endif
  return record;
}

// The normal components of the axes, the height and the image.
void completeRecord(ivec2 at, inout Record record) {
#if RECORDS_8BIT
  vec4 b = texelFetch(uRecordsB, at, 0);
  record.height = signedByte(b.x) * uHeightScale;
  record.axisU.z = signedByte(b.y) * uAxisScale;
  record.axisV.z = signedByte(b.z) * uAxisScale;
  record.image = floor(b.w * 255.0 + 0.5);
#else
  vec2 c = texelFetch(uRecordsC, at, 0).xy;
  record.axisU.z = c.x;
  record.axisV.z = c.y;
#endif
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
    ivec2 at = ivec2(r % kRecordsPerRow, r / kRecordsPerRow);
    Record record = fetchPlanar(at);
#if PARALLAX
    completeRecord(at, record);  // the ray's crossing depends on the heights
#endif
    // Solve centre + s·a + t·b = plane + (height + s·axisU.z + t·axisV.z)·slope for (s, t).
    vec2 a = record.axisU.xy - record.axisU.z * slope;
    vec2 c = record.axisV.xy - record.axisV.z * slope;
    float det = a.x * c.y - a.y * c.x;
    if (abs(det) < 1e-12) continue;  // the ray runs along the leaf
    mat2 inverse = mat2(c.y, -a.y, -c.x, a.x) / det;
    vec2 st = inverse * (plane - record.center + record.height * slope);
    if (any(greaterThan(abs(st), vec2(1.0)))) continue;
#if !PARALLAX
    completeRecord(at, record);
#endif
    vec3 leafNormal = cross(record.axisU, record.axisV);  // the front, as the reference winds it
    bool front = dot(leafNormal, viewer) > 0.0;
    vec2 uv = st * 0.5 + 0.5;
    vec4 texel = textureGrad(uLeaves, vec3(uv, 2.0 * record.image + (front ? 0.0 : 1.0)),
                             0.5 * (inverse * planeDx), 0.5 * (inverse * planeDy));
    // One leaf's image, tested at 0.5 as the reference tests its leaf cards (coverage_test.glsl).
    if (texel.a < 0.5) continue;
    if (uLeavesBinaryAlpha != 0) texel.rgb /= texel.a;
#if PARALLAX
    float z = record.height + st.x * record.axisU.z + st.y * record.axisV.z;
    vec4 clip = uViewProjection *
                vec4(vWorldPosition + vScale * z * (n + slope.x * t + slope.y * b), 1.0);
    gl_FragDepth = clip.z / clip.w * 0.5 + 0.5;
#endif
#ifdef CANOPY_LIT
    vec4 corners = texelFetch(uAmbientOcclusion, at, 0);
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
    // The texel's coverage a counts every leaf of the cell, the walked ones too, which missed
    // this fragment. The rest, a share r of the list, covers 1 - (1 - a)^r of the texel if
    // leaves overlap independently; testing a itself counts the walked leaves twice.
    float coverage = texel.a;
    if (uLowResRestOnly != 0)
      coverage = 1.0 - pow(max(1.0 - texel.a, 0.0), float(listLength - budget) / float(listLength));
    if (coverage >= coverageThreshold(true)) {
      if (uLowResBinaryAlpha != 0) texel.rgb /= texel.a;
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
