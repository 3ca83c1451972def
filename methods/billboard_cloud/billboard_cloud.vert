#version 430 core
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;     // in the atlas
layout(location = 4) in mat4 inModel;  // per instance, locations 4..7

uniform mat4 uViewProjection;

out vec3 vNormal;
out vec2 vUv;

void main() {
  vNormal = mat3(inModel) * inNormal;
  vUv = inUv;
  gl_Position = uViewProjection * (inModel * vec4(inPosition, 1.0));
}
