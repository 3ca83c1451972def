#version 450 core
// The textures of the two closest input cameras, weighted by angle, premultiplied for the over
// operator (§6). Tiles are sRGB in an array texture (decoded by the sampler, filtered
// bilinearly within the tile); outside its tile a camera's texture adds nothing.
uniform sampler2DArray uAtlas;
uniform int uTexels;
uniform float uPageSize;
uniform float uWeight0;
uniform float uWeight1;

flat in vec3 vOrigin0;
flat in vec3 vOrigin1;
in vec2 vTexel0;
in vec2 vTexel1;
out vec4 fragColor;

vec4 lookup(vec3 origin, vec2 texel) {
  float m = float(uTexels);
  if (origin.z < 0.0 || any(lessThan(texel, vec2(0.0))) || any(greaterThan(texel, vec2(m))))
    return vec4(0.0);
  // Texel centres only, so the bilinear footprint never reaches a neighbouring tile.
  vec2 inside = clamp(texel, vec2(0.5), vec2(m - 0.5));
  vec4 c = texture(uAtlas, vec3((origin.xy + inside) / uPageSize, origin.z));
  return vec4(c.rgb * c.a, c.a);
}

void main() {
  vec4 color = uWeight0 * lookup(vOrigin0, vTexel0) + uWeight1 * lookup(vOrigin1, vTexel1);
  if (color.a < 1.0 / 1024.0) discard;
  fragColor = color;
}
