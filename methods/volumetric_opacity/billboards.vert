#version 450 core
// One screen-aligned billboard per non-empty cell (§6), pulled from storage buffers in the
// back-to-front order of the draw's direction; no vertex attributes.
layout(std430, binding = 0) readonly buffer CellCoords { uint cellCoords[]; };
layout(std430, binding = 1) readonly buffer CellOrders { uint cellOrder[]; };
layout(std430, binding = 2) readonly buffer TileTable { uint tileOf[]; };

uniform mat4 uModel;
uniform mat4 uView;
uniform mat4 uProjection;
uniform vec3 uRootMin;
uniform float uCellSize;
uniform int uCells;
uniform int uOrderOffset;
uniform int uCamera0;  // the two input cameras closest in direction
uniform int uCamera1;
uniform vec3 uRight;  // world-space image axes of the viewer
uniform vec3 uUp;
uniform vec2 uHalf;  // world-space half extents of every billboard
uniform int uTexels;

flat out uint vTile0;
flat out uint vTile1;
out vec2 vTexel;

const uint kNoTile = 0xffffffffu;
const vec2 kCorners[6] = vec2[](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1),
                                vec2(0, 1));

void main() {
  uint k = uint(gl_VertexID) / 6u;
  vec2 corner = kCorners[uint(gl_VertexID) % 6u];
  uint cell = cellOrder[uint(uOrderOffset) + k];
  vTile0 = tileOf[uint(uCamera0) * uint(uCells) + cell];
  vTile1 = tileOf[uint(uCamera1) * uint(uCells) + cell];
  if (vTile0 == kNoTile && vTile1 == kNoTile) {
    gl_Position = vec4(0.0, 0.0, -2.0, 1.0);  // outside the clip volume: nothing to draw
    vTexel = vec2(0.0);
    return;
  }
  uint coords = cellCoords[cell];
  vec3 lattice = vec3(float(coords & 1023u), float((coords >> 10) & 1023u),
                      float((coords >> 20) & 1023u));
  vec3 center = (uModel * vec4(uRootMin + (lattice + 0.5) * uCellSize, 1.0)).xyz;
  vec3 position = center + uRight * ((2.0 * corner.x - 1.0) * uHalf.x) +
                  uUp * ((2.0 * corner.y - 1.0) * uHalf.y);
  gl_Position = uProjection * uView * vec4(position, 1.0);
  vTexel = vec2(corner.x, 1.0 - corner.y) * float(uTexels);  // texel rows from the top
}
