#version 430 core
// Position, normal, uv meshes drawn per instance (wood, polygonal leaves, billboards).
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in float inOcclusion;  // ambient occlusion per vertex, when uHasVertexOcclusion
layout(location = 4) in mat4 inModel;  // per instance, locations 4..7

uniform mat4 uViewProjection;
uniform int uHasVertexOcclusion;  // 0 (the default): no occlusion attribute, vOcclusion = 1

out vec3 vNormal;
out vec2 vUv;
out vec3 vWorldPosition;
out float vOcclusion;

void main() {
  vec4 world = inModel * vec4(inPosition, 1.0);
  // Instances are rotations about up and uniform scales, so the model matrix maps normals too.
  vNormal = mat3(inModel) * inNormal;
  vUv = inUv;
  vOcclusion = uHasVertexOcclusion != 0 ? inOcclusion : 1.0;
  vWorldPosition = world.xyz;
  gl_Position = uViewProjection * world;
}
