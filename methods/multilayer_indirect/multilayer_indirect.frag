#version 430 core
// Multi-layer indirect texturing, single pass (García et al. 2007 §5, Fig. 7): the hash cell
// names a list of leaf fragments; walk it from the end facing the viewer until an opaque leaf
// texel; evaluate at most a number of entries that falls with the projected size of a hash texel
// (§5.1) and take the missing leaves from one fetch of the low-resolution texture.
in vec3 vNormal;
in vec2 vUv;
in vec2 vLowResUv;
flat in ivec4 vHash;
flat in vec2 vHalfExtents;
flat in vec3 vTangent;

uniform usampler2D uHash;        // R32UI: (list start << 8) | list length, 0 when empty
uniform sampler2D uLists;        // RGBA16F: leaf position (xy, plane units), image side, image
uniform sampler2DArray uLeaves;  // oriented leaf images, sRGB
uniform sampler2D uLowRes;       // the layered representation, captured at low resolution
uniform sampler2D uAmbientOcclusion;  // RGBA8 like the lists: ambient term at the sprite's corners
uniform int uListsWidth;
uniform int uImagesPerSide;      // tilts × rotations: offset between front and back images
uniform int uRotations;          // orientation bins of the Leaves Texture
uniform int uTilts;
uniform float uLodFactor;        // entries = factor × projected hash-texel diagonal (px); 0: all
uniform float uTargetPixelsPerOutputPixel;  // supersampling: derivatives count target pixels
#include "methods/common/lighting.glsl"
uniform sampler2D uLowResOcclusion;  // AO over the low-resolution atlas (R)
uniform int uHasLowResOcclusion;
uniform int uListsPacked;        // 1: RGBA8 lists (position in its cell, size fraction, image)
uniform float uPositionRange;    // packed positions span [-range, 1 + range] cells
uniform float uMaxSpriteSize;    // packed sizes are fractions of it (plane units)

out vec4 outColor;

// Albedo, or two-sided Lambert (normal facing the viewer) whose ambient term is scaled by the
// ambient occlusion (§5.2).
vec3 shade(vec3 albedo, float occlusion, vec3 normal) { return albedo * lighting(normal, occlusion); }

// The normal of a leaf drawn with oriented image `index` (relative to the billboard's front):
// in the billboard frame it leans from the billboard normal by the bin's mean foreshortening,
// across the leaf's axis, to the side `roll` says (§5.2 relighting, flat leaves). Returned facing
// the viewer's side of the leaf.
vec3 leafNormal(int index, float roll, bool fromFront) {
  int rotation = index % uRotations;
  int tilt = (index / uRotations) % uTilts;
  bool back = (index / uImagesPerSide) % 2 == 1;
  float angle = float(rotation) * 6.28318530718 / float(uRotations);
  vec2 across = vec2(-sin(angle), cos(angle));
  float facing = (float(tilt) + 0.5) / float(uTilts);
  vec3 local = vec3(roll * sqrt(max(1.0 - facing * facing, 0.0)) * across, back ? -facing : facing);
  vec3 n = normalize(vNormal);
  vec3 t = normalize(vTangent - dot(vTangent, n) * n);
  vec3 leaf = normalize(local.x * t + local.y * cross(n, t) + local.z * n);
  return ((dot(leaf, n) >= 0.0) == fromFront) ? leaf : -leaf;
}

void main() {
  vec2 grid = vUv * vec2(vHash.zw);
  ivec2 cell = clamp(ivec2(floor(grid)), ivec2(0), vHash.zw - 1);
  uint cellWord = texelFetch(uHash, vHash.xy + cell, 0).r;
  if (cellWord == 0u) discard;
  int start = int(cellWord >> 8u);
  int listLength = int(cellWord & 255u);
  vec2 plane = (vUv * 2.0 - 1.0) * vHalfExtents;
  vec2 planeDx = dFdx(plane), planeDy = dFdy(plane);
  int budget = listLength;
  if (uLodFactor > 0.0) {
    // In output pixels, as every LoD decision (FrameContext), whatever the supersampling.
    float pixelsPerCell = 1.0 / max(max(length(dFdx(grid)), length(dFdy(grid))), 1e-6) /
                          uTargetPixelsPerOutputPixel;
    budget = min(listLength, int(ceil(uLodFactor * 1.41421356 * pixelsPerCell)));
  }
  bool fromFront = gl_FrontFacing;  // billboards are counter-clockwise seen from their front
  for (int i = 0; i < budget; ++i) {
    int k = start + (fromFront ? i : listLength - 1 - i);
    vec4 entry = texelFetch(uLists, ivec2(k % uListsWidth, k / uListsWidth), 0);
    if (uListsPacked != 0) {  // back to plane units
      vec2 cellSize = 2.0 * vHalfExtents / vec2(vHash.zw);
      vec2 inCell = entry.xy * (1.0 + 2.0 * uPositionRange) - uPositionRange;
      float packedImage = floor(entry.w * 255.0 + 0.5);  // bit 7: the leaf leans back
      float image = mod(packedImage, 128.0);
      entry = vec4(-vHalfExtents + (vec2(cell) + inCell) * cellSize, entry.z * uMaxSpriteSize,
                   packedImage >= 128.0 ? -image - 1.0 : image);
    }
    float roll = entry.w < 0.0 ? -1.0 : 1.0;
    entry.w = entry.w < 0.0 ? -entry.w - 1.0 : entry.w;
    vec2 local = (plane - entry.xy) / entry.z + 0.5;
    if (any(lessThan(local, vec2(0.0))) || any(greaterThanEqual(local, vec2(1.0)))) continue;
    float image = entry.w;
    if (!fromFront) {  // seen from behind: the other side of the same orientation
      int perSide = uImagesPerSide;
      int index = int(image + 0.5);
      bool back = (index / perSide) % 2 == 1;
      image = float(back ? index - perSide : index + perSide);
    }
    vec4 texel = textureGrad(uLeaves, vec3(local, image), planeDx / entry.z, planeDy / entry.z);
    if (texel.a >= 0.5) {
#ifdef CANOPY_LIT
      vec4 corners = texelFetch(uAmbientOcclusion, ivec2(k % uListsWidth, k / uListsWidth), 0);
      float occlusion =
          mix(mix(corners.x, corners.y, local.x), mix(corners.w, corners.z, local.x), local.y);
      outColor = vec4(shade(texel.rgb, occlusion, leafNormal(int(entry.w + 0.5), roll, fromFront)),
                      1.0);
#else
      outColor = vec4(texel.rgb, 1.0);  // unlit: albedo (lit-only work is compiled out)
#endif
      return;
    }
  }
  if (budget < listLength) {
    vec4 texel = texture(uLowRes, vLowResUv);
    if (texel.a >= 0.5) {
#ifdef CANOPY_LIT
      float occlusion = uHasLowResOcclusion != 0 ? texture(uLowResOcclusion, vLowResUv).r : 1.0;
      outColor =
          vec4(shade(texel.rgb, occlusion, normalize(gl_FrontFacing ? vNormal : -vNormal)), 1.0);
#else
      outColor = vec4(texel.rgb, 1.0);
#endif
      return;
    }
  }
  discard;
}
