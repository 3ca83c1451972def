// The alpha test of a baked texel whose alpha is the share of it that leaves cover (the bakes
// sample each texel 4×4). A fixed threshold of 0.5 makes partial coverage all or nothing: texels
// of a sparse crown (alpha below 0.5) vanish and dense ones fill, so far crowns thin out. A
// threshold hashed per target pixel and primitive keeps each texel's coverage in expectation (the
// supersampled target averages it), and overlapping planes, each with its own thresholds, combine
// as independent coverage does (1 - (1 - a)(1 - b)). Same pixel, same primitive, same threshold:
// the images stay deterministic.

// pcg3d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020).
uvec3 coverageHash(uvec3 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  v ^= v >> 16u;
  v.x += v.y * v.z;
  v.y += v.z * v.x;
  v.z += v.x * v.y;
  return v;
}

// The threshold a texel's coverage must reach: hashed for a texture of aggregate coverage (a
// cell's many leaves in one texel: the indirect methods' low-resolution textures), 0.5 for one of
// leaf outlines (the classic cloud's atlas, the list walks' leaf images). Leaf images are tested
// as the reference tests its leaf cards, so that the two thin out alike where leaves are minified:
// hashing the walks' leaf images measured 1.7 to 9 dB worse at 1.5 and 4 radii. The classic atlas
// hashed from its first mip level on measured 0.1 to 0.5 dB better at 12 radii, but its captured
// wood then covered less of what the mesh covers (docs/METHODS.md, "Hashed coverage"); it is the
// classic cloud's `alpha_test: "hashed"` (minifiedCoverageThreshold).
float coverageThreshold(bool aggregate) {
  if (!aggregate) return 0.5;
  uvec3 key = uvec3(uvec2(gl_FragCoord.xy), uint(gl_PrimitiveID));
  return (float(coverageHash(key).x >> 8u) + 0.5) / 16777216.0;
}

// Leaf outlines where a texel is magnified, aggregate coverage where the mip levels average
// several texels: the threshold moves from 0.5 to the hashed one as the sampled level of detail
// goes from 0 to 1, so no line marks the switch.
float minifiedCoverageThreshold(float lod) {
  return mix(0.5, coverageThreshold(true), clamp(lod, 0.0, 1.0));
}
