#pragma once

#include <string>
#include <vector>

#include "common/tree.h"

namespace canopy {

struct TreeFileOptions {
  std::string path;                        // OBJ, glTF/GLB, FBX, Collada (anything Assimp reads)
  std::vector<std::string> leafMaterials;  // materials that are leaves; empty: the automatic rule
  std::string up = "y";                    // the file's up axis: "y" or "z" (converted to Y-up)
};

// Loads a tree asset. Leaves are the faces of leaf materials (alpha-textured, or named like
// leaf/leaves/foliage/needle, unless leafMaterials overrides), split into one Leaf per connected
// component; everything else is wood. Texture coordinates follow Canopy's convention (v = 0 at
// the top image row). Bad input throws InputError naming the file and the problem.
Tree loadTreeFile(const TreeFileOptions& options);

// Whether a material name matches the automatic leaf rule (case-insensitive substring).
bool isLeafMaterialName(const std::string& name);

}  // namespace canopy
