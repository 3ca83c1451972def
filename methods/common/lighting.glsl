// Lighting every lit shader shares (each includes this file): two-sided Lambert with an ambient
// term, and a directional light's shadow map rendered with the same method — impostors cast the
// shadows they look like (multi-layer paper §5.2). Programs that include it are built twice
// (gl::selectLitVariant): CANOPY_LIT defined for lit frames; without it lighting() is 1 and
// lit-only code compiles away, since a CPU rasteriser pays for code behind uniform branches.
uniform int uLit;              // 0: albedo only
uniform vec3 uLightDirection;  // unit, towards the light (world)
uniform float uAmbient;        // share of the ambient term
uniform int uUseAmbientOcclusion;  // 0: baked occlusion is ignored (views.ambient_occlusion false)

#ifdef CANOPY_LIT
in vec3 vWorldPosition;
uniform int uShadows;  // 1: uShadowMap holds the light's depth
uniform sampler2DShadow uShadowMap;
uniform mat4 uLightViewProjection;

// Fraction of the light reaching world point `position`: 3×3 percentage-closer filtering.
float lightVisibilityAt(vec3 position, vec3 normal) {
  if (uShadows == 0) return 1.0;
  vec4 p = uLightViewProjection * vec4(position, 1.0);
  vec3 q = p.xyz / p.w * 0.5 + 0.5;
  if (any(lessThan(q, vec3(0.0))) || any(greaterThan(q, vec3(1.0)))) return 1.0;
  float slope = 1.0 - abs(dot(normal, uLightDirection));
  float bias = 0.0015 + 0.003 * slope;
  vec2 texel = 1.0 / vec2(textureSize(uShadowMap, 0));
  float sum = 0.0;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x)
      sum += texture(uShadowMap, vec3(q.xy + vec2(x, y) * texel, q.z - bias));
  return sum / 9.0;
}

// The factor albedo is multiplied by at world point `position` (impostors that reconstruct the
// surface pass its point, not the quad's): `normal` faces the viewer, `occlusion` scales the
// ambient.
float lightingAt(vec3 position, vec3 normal, float occlusion) {
  if (uLit == 0) return 1.0;
  return uAmbient * (uUseAmbientOcclusion != 0 ? occlusion : 1.0) +
         (1.0 - uAmbient) * max(dot(normal, uLightDirection), 0.0) *
             lightVisibilityAt(position, normal);
}
float lighting(vec3 normal, float occlusion) { return lightingAt(vWorldPosition, normal, occlusion); }
#else
float lightingAt(vec3 position, vec3 normal, float occlusion) { return 1.0; }
float lighting(vec3 normal, float occlusion) { return 1.0; }
#endif
