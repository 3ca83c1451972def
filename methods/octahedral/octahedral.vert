#version 430 core
// One camera-facing quad per instance, no vertex attributes (a 4-vertex strip). The octahedral
// cell of the view direction picks three frames and their weights (octahedral_mapping.cpp holds
// the same functions); the quad spans the bounding sphere's silhouette on the plane through its
// centre, so every reprojected surface point lies behind some quad fragment.
layout(location = 4) in mat4 inModel;  // per instance, locations 4..7
// Each frame's covered rectangle in its image coordinates (x0, y0, x1, y1; −1 … 1 across the
// sphere), frame (i, j) at j · N + i; empty frames have x0 > x1.
layout(std430, binding = 0) readonly buffer FrameRects { vec4 frameRects[]; };

uniform mat4 uViewProjection;
uniform vec3 uEye;           // world: the camera (perspective views)
uniform vec3 uForward;       // world: the view direction (orthographic views, e.g. the shadow map)
uniform int uOrthographic;
uniform vec3 uViewer;        // world: the viewer whose output pixels choose the mip level
uniform float uLodFocalPixels;
uniform float uMaxLod;
uniform vec3 uCenter;        // bounding sphere (tree space)
uniform float uRadius;
uniform int uFrames;         // N
uniform int uHemisphere;
uniform int uBlendFrames;    // 3: barycentric blend; 1: the nearest frame alone
uniform float uInnerTexels;  // texels per side of one frame's image
uniform float uCellUv;       // one cell's side in atlas uv (1 / N)
uniform float uPaddingUv;    // a cell's padding in atlas uv

flat out vec3 vRight[3];     // each frame's image axes and direction towards its camera
flat out vec3 vUp[3];
flat out vec3 vToCamera[3];
flat out vec2 vOrigin[3];    // atlas uv of each frame's image corner (−R, −R)
flat out vec3 vWeights;
flat out mat4 vModel;
flat out vec3 vEyeLocal;     // the camera in tree space (perspective), or
flat out vec3 vForwardLocal; // the view direction in tree space (orthographic)
flat out float vLod;
out vec3 vLocalPosition;     // the quad point in tree space
out vec3 vWorldPosition;

vec3 decodeDirection(vec2 p) {
  vec3 d;
  if (uHemisphere != 0) {
    vec2 q = vec2(0.5 * (p.x + p.y), 0.5 * (p.x - p.y));
    d = vec3(q.x, 1.0 - abs(q.x) - abs(q.y), q.y);
  } else {
    d = vec3(p.x, 1.0 - abs(p.x) - abs(p.y), p.y);
    if (d.y < 0.0) {
      vec2 s = vec2(d.x >= 0.0 ? 1.0 : -1.0, d.z >= 0.0 ? 1.0 : -1.0);
      d.xz = (1.0 - abs(d.zx)) * s;
    }
  }
  return normalize(d);
}

vec2 encodeDirection(vec3 d) {
  if (uHemisphere != 0 && d.y < 0.0) {
    d.y = 0.0;
    d = length(d) > 1e-6 ? normalize(d) : vec3(1.0, 0.0, 0.0);
  }
  vec2 q = d.xz / max(abs(d.x) + abs(d.y) + abs(d.z), 1e-20);
  if (uHemisphere != 0) return vec2(q.x + q.y, q.x - q.y);
  if (d.y >= 0.0) return q;
  return (1.0 - abs(q.yx)) * vec2(q.x >= 0.0 ? 1.0 : -1.0, q.y >= 0.0 ? 1.0 : -1.0);
}

void setFrame(int k, ivec2 frame) {
  vec3 toCamera = decodeDirection(vec2(frame) / float(uFrames - 1) * 2.0 - 1.0);
  vec3 reference = abs(toCamera.y) > 0.999 ? vec3(0.0, 0.0, -1.0) : vec3(0.0, 1.0, 0.0);
  vec3 right = normalize(cross(reference, toCamera));
  vRight[k] = right;
  vUp[k] = cross(toCamera, right);
  vToCamera[k] = toCamera;
  vOrigin[k] = vec2(frame) * uCellUv + uPaddingUv;
}

void main() {
  mat4 toLocal = inverse(inModel);
  vModel = inModel;
  vEyeLocal = (toLocal * vec4(uEye, 1.0)).xyz;
  vForwardLocal = normalize(mat3(toLocal) * uForward);
  vec3 toViewer = uOrthographic != 0 ? -vForwardLocal : vEyeLocal - uCenter;
  float distance = length(toViewer);
  vec3 direction = uOrthographic != 0 ? toViewer : toViewer / max(distance, 1e-6);

  // The grid triangle around the direction and its barycentric weights.
  float last = float(uFrames - 1);
  vec2 g = clamp((encodeDirection(direction) * 0.5 + 0.5) * last, 0.0, last);
  ivec2 cell = min(ivec2(floor(g)), ivec2(uFrames - 2));
  vec2 f = g - vec2(cell);
  ivec2 frames[3];
  vec3 weights;
  if (f.x + f.y <= 1.0) {
    frames = ivec2[3](cell, cell + ivec2(1, 0), cell + ivec2(0, 1));
    weights = vec3(1.0 - f.x - f.y, f.x, f.y);
  } else {
    frames = ivec2[3](cell + ivec2(1, 1), cell + ivec2(0, 1), cell + ivec2(1, 0));
    weights = vec3(f.x + f.y - 1.0, 1.0 - f.x, 1.0 - f.y);
  }
  if (uBlendFrames == 1) {
    int best = weights.y > weights.x ? (weights.z > weights.y ? 2 : 1) : (weights.z > weights.x ? 2 : 0);
    frames[0] = frames[best];
    weights = vec3(1.0, 0.0, 0.0);
  }
  for (int k = 0; k < 3; ++k) setFrame(k, frames[k]);
  vWeights = weights;

  // The mip level: frame texels per output pixel at the viewer's distance.
  float scale = length(inModel[0].xyz);
  float viewerDistance = length(uViewer - (inModel * vec4(uCenter, 1.0)).xyz);
  float texelsPerPixel =
      uInnerTexels / (2.0 * uRadius * scale) * viewerDistance / max(uLodFocalPixels, 1e-6);
  vLod = clamp(log2(max(texelsPerPixel, 1.0)), 0.0, uMaxLod);

  // The quad: perpendicular to the view through the sphere's centre, cut to where the chosen
  // frames' covered rectangles, each a box through the sphere's depth along its frame, project
  // (from the eye, or along the view for orthographic frames). Within the sphere's silhouette.
  vec3 w = -direction;
  vec3 reference = abs(w.y) > 0.999 ? vec3(0.0, 0.0, -1.0) : vec3(0.0, 1.0, 0.0);
  vec3 right = normalize(cross(reference, -w));
  vec3 up = cross(-w, right);
  float halfSide = uRadius;
  if (uOrthographic == 0)
    halfSide = min(uRadius * distance / sqrt(max(distance * distance - uRadius * uRadius,
                                              0.0625 * uRadius * uRadius)), 4.0 * uRadius);
  vec2 lo = vec2(halfSide), hi = vec2(-halfSide);
  bool whole = false;  // a box corner behind the eye: the silhouette square
  for (int k = 0; k < 3; ++k) {
    vec4 r = frameRects[frames[k].y * uFrames + frames[k].x];
    if (vWeights[k] <= 0.0 || r.x > r.z) continue;
    for (int c = 0; c < 8; ++c) {
      vec3 corner = uCenter + uRadius * (vRight[k] * ((c & 1) != 0 ? r.z : r.x) +
                                         vUp[k] * ((c & 2) != 0 ? r.w : r.y) +
                                         vToCamera[k] * ((c & 4) != 0 ? 1.0 : -1.0));
      vec3 offset = corner - uCenter;
      if (uOrthographic == 0) {
        float along = dot(corner - vEyeLocal, w);  // distance in front of the eye
        if (along < 0.05 * uRadius) whole = true;
        offset = vEyeLocal + (corner - vEyeLocal) * (distance / max(along, 1e-6)) - uCenter;
      }
      vec2 q = vec2(dot(offset, right), dot(offset, up));
      lo = min(lo, q);
      hi = max(hi, q);
    }
  }
  if (whole) lo = vec2(-halfSide), hi = vec2(halfSide);
  lo = max(lo, vec2(-halfSide));
  hi = max(min(hi, vec2(halfSide)), lo);
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  vLocalPosition = uCenter + right * mix(lo.x, hi.x, corner.x) + up * mix(lo.y, hi.y, corner.y);
  vec4 world = inModel * vec4(vLocalPosition, 1.0);
  vWorldPosition = world.xyz;
  gl_Position = uViewProjection * world;
}
