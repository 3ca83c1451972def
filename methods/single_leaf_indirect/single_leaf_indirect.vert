#version 430 core
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;      // over the billboard, [0, 1]²
layout(location = 3) in ivec4 inGrid;   // first cell in the index atlas (xy), cells (zw)
layout(location = 4) in mat4 inModel;   // per instance, locations 4..7
layout(location = 8) in int inReach;    // the cells a fragment looks at (single_leaf_indirect.cpp)
layout(location = 9) in vec2 inLowResUv;  // in the low-resolution atlas
// With LOWRES_TEXTURE (inserted after the #version line by the method) it feeds
// alpha_tested_texture.frag the low-resolution atlas uv instead (lod_lowres_px).

uniform mat4 uViewProjection;

out vec3 vNormal;
out vec3 vWorldPosition;
out vec2 vUv;
flat out ivec4 vGrid;
flat out int vReach;

void main() {
  vNormal = mat3(inModel) * inNormal;
#ifdef LOWRES_TEXTURE
  vUv = inLowResUv;
#else
  vUv = inUv;
#endif
  vGrid = inGrid;
  vReach = inReach;
  vec4 world = inModel * vec4(inPosition, 1.0);
  vWorldPosition = world.xyz;
  gl_Position = uViewProjection * world;
}
