#pragma once

#include <filesystem>

#include "common/tree.h"

namespace canopy {

// Writes a tree as Wavefront OBJ + MTL + PNG textures into `folder` (<name>.obj), the layout
// Blender and most tools read: wood under material "bark", each leaf texture as material
// "leaf_<i>" with map_Kd/map_d, every leaf one quad with uvs in the OBJ convention (v up).
// Returns the OBJ path.
std::filesystem::path exportTreeObj(const Tree& tree, const std::filesystem::path& folder);

}  // namespace canopy
