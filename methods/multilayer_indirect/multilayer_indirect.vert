#version 430 core
// The billboards of the multi-layer method, pulled from one 48-byte record per billboard (no
// vertex or index buffer: four 48-byte corners and six indices per billboard were a third of the
// method's memory). Drawn with DrawArrays, six vertices per billboard: gl_VertexID / 6 names the
// billboard (or its slot in a view order), gl_VertexID % 6 its corner. With FAR_LEVEL (defined before this line by the method)
// it feeds alpha_tested_texture.frag the low-resolution atlas uv instead.
layout(location = 4) in mat4 inModel;  // per instance, locations 4..7

// Per billboard, three uvec4 (multilayer_indirect.cpp, BillboardRecord):
//   [0] centre xyz (float bits), normal (2_10_10_10 snorm)
//   [1] half extents xy (float bits), axisU (2_10_10_10 snorm), first leaf record
//   [2] hash origin (x | y << 16), hash cells (x | y << 16),
//       low-resolution texel origin (x | y << 16), texel size (x | y << 16)
layout(std430, binding = 0) readonly buffer Billboards { uvec4 billboards[]; };
// With view_orders the draw's slots name billboards through 16-bit entries, two to a word, the
// walked clouds sorted front to back per view direction (view_orders.h).
layout(std430, binding = 1) readonly buffer Orders { uint orders[]; };
uniform int uOrdered;

uniform mat4 uViewProjection;
uniform vec2 uLowResAtlasSize;  // texels

out vec3 vNormal;
out vec3 vWorldPosition;
out vec2 vUv;
#ifndef FAR_LEVEL
out vec2 vLowResUv;
flat out ivec4 vHash;
flat out vec2 vHalfExtents;
flat out vec3 vTangent;
flat out int vRecordBase;
flat out float vScale;  // the instance's scale: billboard units to world units
#endif

vec3 unpackSnorm10(uint word) {
  ivec3 q = ivec3(bitfieldExtract(int(word), 0, 10), bitfieldExtract(int(word), 10, 10),
                  bitfieldExtract(int(word), 20, 10));
  return max(vec3(q) / 511.0, vec3(-1.0));
}

uvec2 unpackPair(uint word) { return uvec2(word & 0xffffu, word >> 16u); }

void main() {
  const int kCorners[6] = int[6](0, 1, 2, 0, 2, 3);  // two triangles, CCW from (−,−)
  int slot = gl_VertexID / 6;
  int billboard =
      uOrdered != 0 ? int(bitfieldExtract(orders[slot >> 1], 16 * (slot & 1), 16)) : slot;
  int corner = kCorners[gl_VertexID % 6];
  uvec4 a = billboards[3 * billboard], b = billboards[3 * billboard + 1],
        c = billboards[3 * billboard + 2];
  vec3 center = uintBitsToFloat(a.xyz);
  vec2 halfExtents = uintBitsToFloat(b.xy);
  vec3 n = normalize(unpackSnorm10(a.w));
  // The frame the fragment shader uses: axisU made orthogonal to the (quantized) normal.
  vec3 tangent = normalize(unpackSnorm10(b.z) - dot(unpackSnorm10(b.z), n) * n);
  vec3 bitangent = cross(n, tangent);
  // (−,−) (+,−) (+,+) (−,+): the corner's place on the billboard.
  vec2 uv = vec2(corner == 1 || corner == 2 ? 1.0 : 0.0, corner >= 2 ? 1.0 : 0.0);
  vec2 lowResUv = (vec2(unpackPair(c.z)) + uv * vec2(unpackPair(c.w))) / uLowResAtlasSize;
  vec3 position = center + tangent * ((2.0 * uv.x - 1.0) * halfExtents.x) +
                  bitangent * ((2.0 * uv.y - 1.0) * halfExtents.y);

  vec4 world = inModel * vec4(position, 1.0);
  vWorldPosition = world.xyz;
  // Instances are rotations about up and uniform scales, so the model matrix maps normals too.
  vNormal = mat3(inModel) * n;
#ifdef FAR_LEVEL
  vUv = lowResUv;
#else
  vUv = uv;
  vLowResUv = lowResUv;
  vHash = ivec4(unpackPair(c.x), unpackPair(c.y));
  vHalfExtents = halfExtents;
  vTangent = mat3(inModel) * tangent;
  vRecordBase = int(b.w);
  vScale = length(vNormal);
#endif
  gl_Position = uViewProjection * world;
}
