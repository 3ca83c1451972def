#version 430 core
// Box quads and polygonal leaves of the bounding-box hierarchy. The instance matrix is affine;
// its unused bottom row carries the dissolve of a level transition: m[0][3] the threshold,
// m[1][3] 1 to keep the pixels below it (the finer level) or 0 to keep those above (the box).
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 4) in mat4 inModel;

uniform mat4 uViewProjection;

out vec3 vNormal;
out vec2 vUv;
flat out vec2 vDissolve;
out vec3 vWorldPosition;

void main() {
  mat4 model = inModel;
  vDissolve = vec2(model[0][3], model[1][3]);
  model[0][3] = 0.0;
  model[1][3] = 0.0;
  vNormal = mat3(model) * inNormal;
  vUv = inUv;
  vec4 world = model * vec4(inPosition, 1.0);
  vWorldPosition = world.xyz;
  gl_Position = uViewProjection * world;
}
