#version 430 core
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;    // unit, or nearly (10-bit components)
layout(location = 2) in vec2 inLowResUv;     // in the low-resolution atlas
layout(location = 4) in mat4 inModel;        // per instance, locations 4..7
layout(location = 8) in ivec4 inHash;        // first cell in the hash atlas (xy), cells (zw)
layout(location = 9) in vec2 inHalfExtents;  // of the billboard rectangle
layout(location = 10) in vec3 inTangent;     // the billboard's first axis
layout(location = 11) in int inRecordBase;   // the billboard's first leaf record

uniform mat4 uViewProjection;

out vec3 vNormal;
out vec3 vWorldPosition;
out vec2 vUv;
out vec2 vLowResUv;
flat out ivec4 vHash;
flat out vec2 vHalfExtents;
flat out vec3 vTangent;
flat out int vRecordBase;
flat out float vScale;  // the instance's scale: billboard units to world units

void main() {
  vNormal = mat3(inModel) * normalize(inNormal);
  vScale = length(vNormal);
  // Four corners per billboard, (−,−) (+,−) (+,+) (−,+): the place on it from the vertex index.
  int corner = gl_VertexID % 4;
  vUv = vec2(corner == 1 || corner == 2 ? 1.0 : 0.0, corner >= 2 ? 1.0 : 0.0);
  vLowResUv = inLowResUv;
  vHash = inHash;
  vHalfExtents = inHalfExtents;
  vTangent = mat3(inModel) * inTangent;
  vRecordBase = inRecordBase;
  vec4 world = inModel * vec4(inPosition, 1.0);
  vWorldPosition = world.xyz;
  gl_Position = uViewProjection * world;
}
