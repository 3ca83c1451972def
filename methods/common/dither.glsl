// Dithered cross-fades between two representations of one instance (the octahedral impostor and
// its mesh): each fragment has a threshold in [0, 1) from a 4×4 Bayer matrix on its pixel, and is
// kept when the threshold lies in [uDitherKeep.x, uDitherKeep.y). Complementary ranges draw every
// pixel exactly once between the two; FrameContext::ditherKeep sets it, {0, 1} keeps everything.
uniform vec2 uDitherKeep;

bool ditherRejects() {
  const float bayer[16] = float[16](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0, 3.0, 11.0, 1.0,
                                    9.0, 15.0, 7.0, 13.0, 5.0);
  ivec2 p = ivec2(gl_FragCoord.xy) & 3;
  float threshold = (bayer[p.y * 4 + p.x] + 0.5) / 16.0;
  return threshold < uDitherKeep.x || threshold >= uDitherKeep.y;
}
