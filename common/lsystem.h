#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/tree.h"

namespace canopy {

// One module of a parametric L-system string: a symbol and up to four parameters.
//   A(l, r, order)       growing apex, rewritten by the productions
//   F(l, r, order)       a branch segment drawn as a cylinder, advancing the turtle
//   +(deg) &(deg) /(deg) turn (about up), pitch (about left), roll (about heading)
//   [ ]                  PUSH / POP: save or restore the turtle and open or close a branch box
//   L(scale, pitch, roll) a leaf placed at the turtle (a FORM: the turtle does not move)
struct Module {
  char symbol = 0;
  float p[4] = {0, 0, 0, 0};

  static Module make(char symbol, float a = 0, float b = 0, float c = 0, float d = 0) {
    return Module{symbol, {a, b, c, d}};
  }
};

// The parameters of the built-in broadleaf-style grammar. Presets are values of this struct.
struct LSystemTreeParams {
  std::string preset;                // preset name, recorded as the tree's name
  int iterations = 7;                // derivation steps of the apex production
  int maxOrder = 4;                  // highest branching order that still spawns laterals
  int stems = 1;                     // trunks rising from the base (shrubs have several)
  float boleLength = 3.0f;           // bare trunk below the first branches (m)
  float trunkLength = 1.6f;          // first internode length above the bole (m)
  float trunkRadius = 0.25f;         // trunk radius at the base (m)
  float mainLengthRatio = 0.88f;     // internode length ratio along an axis
  float lateralLengthRatio = 0.78f;  // length ratio from parent to lateral
  float radiusRatio = 0.72f;         // radius ratio from parent to lateral
  float mainRadiusRatio = 0.86f;     // radius ratio along an axis
  float branchAngle = 42.0f;         // pitch of a lateral from its parent (deg)
  float angleJitter = 12.0f;         // uniform jitter on branch angles (deg)
  float divergence = 137.5f;         // roll between successive laterals (deg)
  float tropism = 0.06f;             // bend of the heading towards gravity per segment (neg. = up)
  float stemSpread = 0.0f;           // pitch of the stems from vertical when stems > 1 (deg)
  int leafOrder = 2;                 // segments of this order or higher carry leaves
  int leaves = 20000;                // leaves to place, exactly
  float leafLength = 0.16f;          // blade length (m)
  float leafWidth = 0.09f;           // blade width (m)
  float leafSizeJitter = 0.2f;       // relative size variation
  float leafPitch = 50.0f;           // angle of the leaf axis from the twig (deg)
  float leafSpread = 0.25f;          // leaves stand up to this far off their twig (m)
  int trunkLaterals = 2;             // laterals per internode on order-0 axes
  int leafTextureVariants = 2;       // procedurally drawn leaf textures to choose from
  int leafTextureSize = 256;         // texels per side of each leaf image
};

// The named presets: broadleaf (~20k leaves), shrub (~2.5k), sparse (~1k).
LSystemTreeParams treePreset(const std::string& name);
std::vector<std::string> treePresetNames();

// Derives the string (productions applied `iterations` times, then leaves distributed).
std::vector<Module> deriveTreeString(const LSystemTreeParams& params, uint64_t seed);

// Interprets a string with a stack-based turtle into a Tree. PUSH/POP create and close branch
// boxes exactly as the bounding-box paper §3.2.1 describes.
Tree interpretTreeString(const std::vector<Module>& modules, const LSystemTreeParams& params,
                         uint64_t seed);

// deriveTreeString + interpretTreeString + procedural leaf textures. Deterministic: the same
// params and seed give a byte-identical tree.
Tree generateTree(const LSystemTreeParams& params, uint64_t seed);

}  // namespace canopy
