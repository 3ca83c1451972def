#version 430 core
// Indirect texturing with one leaf per cell (García et al. 2005): a cell's index names a leaf
// image at a quantized orientation, centred on the cell and as large as the leaf (its own scale,
// so a leaf may reach into the neighbouring cells). The fragment looks at the cells the
// billboard's largest leaf can reach it from (its own; the 2×2 nearest; or a square) and keeps
// the opaque texel of the leaf nearest the viewer's side.
in vec3 vNormal;
in vec2 vUv;
flat in ivec4 vGrid;
flat in int vReach;  // 0: own cell, 1: the 2×2 cells nearest the fragment, r + 1: within r

uniform usampler2D uCells;       // R32UI: 0 empty, else image + 1 | scale·32 << 12 | depth << 20
uniform sampler2DArray uLeaves;  // oriented leaf images, sRGB
uniform int uImagesPerSide;      // tilts × rotations: offset between front and back images
#include "methods/common/lighting.glsl"

out vec4 outColor;

void main() {
  vec2 grid = vUv * vec2(vGrid.zw);
  vec2 gridDx = dFdx(grid), gridDy = dFdy(grid);
  ivec2 own = clamp(ivec2(floor(grid)), ivec2(0), vGrid.zw - 1);
  bool fromFront = gl_FrontFacing;  // billboards are counter-clockwise seen from their front
  float nearest = -1.0;
  vec3 color = vec3(0.0);
  ivec2 lo = own, hi = own;
  if (vReach == 1) {  // a leaf reaches at most half a cell past its own: from the nearest side
    lo = own + ivec2(step(0.5, fract(grid))) - 1;
    hi = lo + 1;
  } else if (vReach > 1) {
    lo = own - (vReach - 1);
    hi = own + (vReach - 1);
  }
  for (int y = lo.y; y <= hi.y; ++y) {
    for (int x = lo.x; x <= hi.x; ++x) {
      ivec2 cell = ivec2(x, y);
      if (any(lessThan(cell, ivec2(0))) || any(greaterThanEqual(cell, vGrid.zw))) continue;
      uint word = texelFetch(uCells, vGrid.xy + cell, 0).r;
      if (word == 0u) continue;
      float scale = float((word >> 12u) & 255u) / 32.0;
      vec2 local = (grid - (vec2(cell) + 0.5)) / scale + 0.5;
      if (any(lessThan(local, vec2(0.0))) || any(greaterThanEqual(local, vec2(1.0)))) continue;
      float depth = float(word >> 20u);  // 0 at the back of the billboard, 4095 at its front
      if (!fromFront) depth = 4095.0 - depth;
      if (depth <= nearest) continue;
      int image = int(word & 4095u) - 1;
      if (!fromFront) {  // seen from behind: the other side of the same orientation
        bool back = (image / uImagesPerSide) % 2 == 1;
        image += back ? -uImagesPerSide : uImagesPerSide;
      }
      vec4 texel = textureGrad(uLeaves, vec3(local, float(image)), gridDx / scale, gridDy / scale);
      if (texel.a < 0.5) continue;
      nearest = depth;
      color = texel.rgb;
    }
  }
  if (nearest < 0.0) discard;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
    color *= lighting(normal, 1.0);
  }
  outColor = vec4(color, 1.0);
}
