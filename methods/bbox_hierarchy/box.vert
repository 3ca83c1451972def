#version 430 core
// Box quads and polygonal leaves of the bounding-box hierarchy. The instance matrix is affine;
// its unused bottom row carries the dissolve of a level transition: m[0][3] the threshold,
// m[1][3] 1 to keep the pixels below it (the finer level) or 0 to keep those above (the box).
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 4) in mat4 inModel;

uniform mat4 uViewProjection;
uniform vec3 uCameraPosition;  // world
// Box quads blended by facing (§4: "alpha-blending the texture-mapped polygons associated to a
// box"): the box's three quad pairs, one unit normal a column, and its centre, in tree space.
uniform int uFacingBlend;  // 1: each pixel shows one quad, chosen by the weights below
uniform float uFacingPower;
uniform mat3 uPairNormals;
uniform vec3 uBoxCenter;

out vec3 vNormal;
out vec2 vUv;
flat out vec2 vDissolve;
// The share of pixels this quad keeps, as a range of the facing dither: [0, w / w_max) with
// w = |n·v|^power, so the most squarely facing quad is opaque and the others fade with their
// angle — order-independent alpha blending whose coverage stays between one quad's and all
// three's. (A partition of [0, 1) by w / Σw, each pixel one quad, lost 0.6 dB at 12 radii.)
flat out vec2 vFacingRange;
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
  vFacingRange = vec2(0.0, 1.0);
  if (uFacingBlend != 0) {
    vec3 toViewer = normalize(uCameraPosition - vec3(model * vec4(uBoxCenter, 1.0)));
    vec3 weights;
    float own = 0.0, alignment = -1.0;
    for (int k = 0; k < 3; ++k) {
      weights[k] = pow(abs(dot(normalize(mat3(model) * uPairNormals[k]), toViewer)), uFacingPower);
      float a = abs(dot(inNormal, uPairNormals[k]));  // which pair this quad belongs to
      if (a > alignment) {
        alignment = a;
        own = weights[k];
      }
    }
    float strongest = max(max(weights.x, weights.y), max(weights.z, 1e-6));
    vFacingRange = vec2(0.0, own >= strongest ? 2.0 : own / strongest);
  }
}
