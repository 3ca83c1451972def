#version 450 core
// One billboard per non-empty cell of the instance's level of detail (§6), pulled from storage
// buffers in the back-to-front order of the draw's direction; no vertex attributes. The quad
// faces the viewer; each of the two input cameras' textures is laid on it in that camera's own
// image axes turned towards the viewer (roll kept), so vTexel0/1 are texel coordinates in each.
layout(std430, binding = 0) readonly buffer CellCoords { uint cellCoords[]; };
// Back-to-front orders (PackedOrders): 16-bit cell indices, two to a word, when uOrders16.
layout(std430, binding = 1) readonly buffer CellOrders { uint cellOrder[]; };
// Per cell: its first tile, then the mask of the views that have one (tiles stored cell by cell).
layout(std430, binding = 2) readonly buffer TileTable { uint tileTable[]; };

uniform mat4 uModel;
uniform mat4 uView;
uniform mat4 uProjection;
uniform vec3 uRootMin;
uniform float uCellSize;
uniform int uCellBase;     // the level's first entry in cellCoords
uniform int uTileBase;     // the level's first entry in tileTable
uniform int uTableStride;  // words per cell in tileTable
uniform int uOrderOffset;  // the stored order's first element in cellOrder
uniform int uOrderReversed;  // 1: the opposite direction's order, walked backwards
uniform int uOrders16;
uniform int uCellCount;  // cells of the level (elements of one order)
uniform int uCamera0;      // the two input cameras closest in direction
uniform int uCamera1;
uniform vec3 uQuadRight;  // model-space axes and half extents of the quad
uniform vec3 uQuadUp;
uniform vec2 uQuadHalf;
uniform vec3 uAxisRight0;  // camera image axes (model space) over the billboard half extents
uniform vec3 uAxisUp0;
uniform vec3 uAxisRight1;
uniform vec3 uAxisUp1;
uniform int uTexels;
uniform int uTilesPerRow;

flat out vec3 vOrigin0;  // the tile's first texel in the atlas (x, y) and its page; page < 0: none
flat out vec3 vOrigin1;
out vec2 vTexel0;
out vec2 vTexel1;

const uint kNoTile = 0xffffffffu;
const vec2 kCorners[6] = vec2[](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1),
                                vec2(0, 1));

uint tileOf(uint camera, uint cell) {
  uint base = uint(uTileBase) + cell * uint(uTableStride);
  uint mask = tileTable[base + 1u + camera / 32u], bit = camera % 32u;
  if (((mask >> bit) & 1u) == 0u) return kNoTile;
  uint index = tileTable[base];
  for (uint w = 0u; w < camera / 32u; ++w) index += uint(bitCount(tileTable[base + 1u + w]));
  return index + uint(bitCount(mask & ((1u << bit) - 1u)));
}

vec3 originOf(uint tile) {
  if (tile == kNoTile) return vec3(0.0, 0.0, -1.0);
  uint perPage = uint(uTilesPerRow * uTilesPerRow);
  uint slot = tile % perPage;
  return vec3(float((slot % uint(uTilesPerRow)) * uint(uTexels)),
              float((slot / uint(uTilesPerRow)) * uint(uTexels)), float(tile / perPage));
}

// Texel coordinates (rows from the billboard's top) of an offset from the cell's centre.
vec2 texelOf(vec3 offset, vec3 axisRight, vec3 axisUp) {
  vec2 unit = vec2(dot(offset, axisRight), dot(offset, axisUp));  // [-1, 1] on the billboard
  return vec2(0.5 + 0.5 * unit.x, 0.5 - 0.5 * unit.y) * float(uTexels);
}

void main() {
  uint k = uint(gl_VertexID) / 6u;
  vec2 corner = kCorners[uint(gl_VertexID) % 6u];
  uint element = uint(uOrderOffset) + (uOrderReversed != 0 ? uint(uCellCount) - 1u - k : k);
  uint cell = uOrders16 != 0 ? (cellOrder[element >> 1] >> (16u * (element & 1u))) & 0xffffu
                             : cellOrder[element];
  uint tile0 = tileOf(uint(uCamera0), cell);
  uint tile1 = tileOf(uint(uCamera1), cell);
  vOrigin0 = originOf(tile0);
  vOrigin1 = originOf(tile1);
  if (tile0 == kNoTile && tile1 == kNoTile) {
    gl_Position = vec4(0.0, 0.0, -2.0, 1.0);  // outside the clip volume: nothing to draw
    vTexel0 = vTexel1 = vec2(0.0);
    return;
  }
  uint coords = cellCoords[uint(uCellBase) + cell];
  vec3 lattice = vec3(float(coords & 1023u), float((coords >> 10) & 1023u),
                      float((coords >> 20) & 1023u));
  vec3 offset = uQuadRight * ((2.0 * corner.x - 1.0) * uQuadHalf.x) +
                uQuadUp * ((2.0 * corner.y - 1.0) * uQuadHalf.y);
  vec3 center = uRootMin + (lattice + 0.5) * uCellSize;
  gl_Position = uProjection * uView * uModel * vec4(center + offset, 1.0);
  vTexel0 = texelOf(offset, uAxisRight0, uAxisUp0);
  vTexel1 = texelOf(offset, uAxisRight1, uAxisUp1);
}
