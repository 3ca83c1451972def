#include "common/tree_export.h"

#include <fmt/format.h>

#include "common/atomic_file.h"
#include "common/image.h"

namespace canopy {

std::filesystem::path exportTreeObj(const Tree& tree, const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder);
  const std::string stem = tree.name.empty() ? "tree" : tree.name;
  std::string mtl;
  for (size_t m = 0; m < tree.woodMaterials.size(); ++m) {
    const WoodMaterial& material = tree.woodMaterials[m];
    mtl += fmt::format("newmtl wood_{}\nKd {} {} {}\n", m, srgbToLinear(material.baseColor.r),
                       srgbToLinear(material.baseColor.g), srgbToLinear(material.baseColor.b));
    if (material.texture >= 0) {
      const std::string image = fmt::format("{}_wood_{}.png", stem, material.texture);
      writePng(folder / image, tree.woodTextures[material.texture]);
      mtl += "map_Kd " + image + "\n";
    }
  }
  for (size_t t = 0; t < tree.leafTextures.size(); ++t) {
    const std::string image = fmt::format("{}_leaf_{}.png", stem, t);
    writePng(folder / image, tree.leafTextures[t].front);
    mtl += fmt::format("newmtl leaf_{}\nKd 1 1 1\nmap_Kd {}\nmap_d {}\n", t, image, image);
  }
  writeTextAtomically(folder / (stem + ".mtl"), mtl);

  std::string obj = fmt::format("# {} exported by Canopy\nmtllib {}.mtl\no wood\n", stem, stem);
  obj.reserve(64 * (tree.wood.positions.size() + tree.leaves.size() * 6));
  const WoodMesh& wood = tree.wood;
  for (const glm::vec3& p : wood.positions) obj += fmt::format("v {} {} {}\n", p.x, p.y, p.z);
  for (const glm::vec2& uv : wood.uvs) obj += fmt::format("vt {} {}\n", uv.x, 1.0f - uv.y);
  for (const glm::vec3& n : wood.normals) obj += fmt::format("vn {} {} {}\n", n.x, n.y, n.z);
  int currentMaterial = -1;
  for (size_t t = 0; t < wood.triangleCount(); ++t) {
    if (wood.materialIds[t] != currentMaterial) {
      currentMaterial = wood.materialIds[t];
      obj += fmt::format("usemtl wood_{}\n", currentMaterial);
    }
    obj += "f";
    for (int k = 0; k < 3; ++k) obj += fmt::format(" {0}/{0}/{0}", wood.indices[t * 3 + k] + 1);
    obj += "\n";
  }
  obj += "o leaves\n";
  const size_t vertexBase = wood.positions.size(), uvBase = wood.uvs.size();
  for (const Leaf& leaf : tree.leaves) {
    for (int c = 0; c < 4; ++c) {
      const glm::vec3 p = leaf.corner(c);
      obj += fmt::format("v {} {} {}\n", p.x, p.y, p.z);
    }
  }
  for (const Leaf& leaf : tree.leaves) {
    for (int c = 0; c < 4; ++c) {
      const glm::vec2 uv = leaf.cornerUv(c);
      obj += fmt::format("vt {} {}\n", uv.x, 1.0f - uv.y);
    }
  }
  int currentTexture = -1;
  for (size_t l = 0; l < tree.leaves.size(); ++l) {
    if (static_cast<int>(tree.leaves[l].texture) != currentTexture) {
      currentTexture = static_cast<int>(tree.leaves[l].texture);
      obj += fmt::format("usemtl leaf_{}\n", currentTexture);
    }
    const size_t v = vertexBase + l * 4 + 1, t = uvBase + l * 4 + 1;
    obj +=
        fmt::format("f {}/{} {}/{} {}/{} {}/{}\n", v, t, v + 1, t + 1, v + 2, t + 2, v + 3, t + 3);
  }
  auto path = folder / (stem + ".obj");
  writeTextAtomically(path, obj);
  return path;
}

}  // namespace canopy
