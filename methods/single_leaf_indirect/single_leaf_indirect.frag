#version 430 core
// Indirect texturing with one leaf per cell: the cell's index names a leaf image at a quantized
// orientation, fetched at the fragment's position inside the cell.
in vec3 vNormal;
in vec2 vUv;
flat in ivec4 vGrid;

uniform usampler2D uCells;        // R16UI: 0 empty, else 1 + leaf image index
uniform sampler2DArray uLeaves;   // oriented leaf images, sRGB
#include "methods/common/lighting.glsl"

out vec4 outColor;

void main() {
  vec2 grid = vUv * vec2(vGrid.zw);
  ivec2 cell = clamp(ivec2(floor(grid)), ivec2(0), vGrid.zw - 1);
  uint reference = texelFetch(uCells, vGrid.xy + cell, 0).r;
  if (reference == 0u) discard;
  // Explicit gradients: the local coordinate jumps at cell borders, the cell scale does not.
  vec4 texel = textureGrad(uLeaves, vec3(grid - vec2(cell), float(reference - 1u)), dFdx(grid), dFdy(grid));
  if (texel.a < 0.5) discard;
  vec3 color = texel.rgb;
  if (uLit != 0) {
    vec3 normal = normalize(gl_FrontFacing ? vNormal : -vNormal);
    color *= lighting(normal, 1.0);
  }
  outColor = vec4(color, 1.0);
}
