#version 450 core
// Shows the method's render (linear, premultiplied, alpha = coverage) over the background, the
// reference on the left of a split, or the per-pixel error between them as a heat map.
uniform sampler2D uMethod;
uniform sampler2D uReference;
uniform int uMode;         // 0 method, 1 split (reference left), 2 error heat map
uniform float uSplit;      // split position in [0, 1]
uniform vec3 uBackground;  // linear
in vec2 vUv;
out vec4 fragColor;

vec3 toSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
vec3 over(vec4 premultiplied) { return premultiplied.rgb + (1.0 - premultiplied.a) * uBackground; }
vec3 heat(float t) {  // black → red → yellow → white
  t = clamp(t, 0.0, 1.0);
  return clamp(vec3(3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0), 0.0, 1.0);
}

void main() {
  vec3 method = toSrgb(over(texture(uMethod, vUv)));
  vec3 reference = toSrgb(over(texture(uReference, vUv)));
  vec3 color = method;
  if (uMode == 1) {
    color = vUv.x < uSplit ? reference : method;
    if (abs(vUv.x - uSplit) < 0.0015) color = vec3(1.0);
  } else if (uMode == 2) {
    // Mean absolute sRGB error, full scale at 0.5 (as the comparison figures).
    color = heat(dot(abs(method - reference), vec3(1.0 / 3.0)) / 0.5);
  }
  fragColor = vec4(color, 1.0);
}
