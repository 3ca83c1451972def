#include "common/tree_loader.h"

#include <assimp/GltfMaterial.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include <spdlog/spdlog.h>
#include <glm/geometric.hpp>

#include "common/error.h"
#include "common/file_checks.h"
#include "common/image.h"

namespace canopy {
namespace fs = std::filesystem;

bool isLeafMaterialName(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  for (const char* word : {"leaf", "leaves", "foliage", "needle"}) {
    if (lower.find(word) != std::string::npos) return true;
  }
  return false;
}

namespace {

struct LoadContext {
  const TreeFileOptions& options;
  const aiScene& scene;
  fs::path directory;
  std::map<std::string, ImageRgba8> imageCache;  // by resolved path or embedded name
};

std::string materialName(const aiMaterial& material) {
  aiString name;
  material.Get(AI_MATKEY_NAME, name);
  return name.C_Str();
}

std::string texturePath(const aiMaterial& material, aiTextureType type) {
  if (material.GetTextureCount(type) == 0) return "";
  aiString path;
  material.GetTexture(type, 0, &path);
  return path.C_Str();
}

bool hasAlphaMode(const aiMaterial& material) {
  aiString mode;
  if (material.Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS) {
    return std::string(mode.C_Str()) != "OPAQUE";
  }
  return false;
}

const ImageRgba8& loadTexture(LoadContext& context, const std::string& reference,
                              const std::string& material) {
  const std::string& file = context.options.path;
  // Embedded textures ("*0" in glTF/GLB, or a name that matches an embedded texture).
  if (const aiTexture* embedded = context.scene.GetEmbeddedTexture(reference.c_str())) {
    auto [it, inserted] = context.imageCache.try_emplace("embedded:" + reference);
    if (inserted) {
      const std::string name =
          file + " (embedded texture " + reference + " of material '" + material + "')";
      if (embedded->mHeight != 0) {
        // Uncompressed BGRA texels.
        ImageRgba8 image(static_cast<int>(embedded->mWidth), static_cast<int>(embedded->mHeight));
        for (size_t i = 0; i < size_t(embedded->mWidth) * embedded->mHeight; ++i) {
          const aiTexel& t = embedded->pcData[i];
          image.pixels[i * 4 + 0] = t.r;
          image.pixels[i * 4 + 1] = t.g;
          image.pixels[i * 4 + 2] = t.b;
          image.pixels[i * 4 + 3] = t.a;
        }
        it->second = std::move(image);
      } else {
        it->second =
            readImageFromMemory(embedded->pcData, embedded->mWidth, embedded->achFormatHint, name);
      }
    }
    return it->second;
  }
  std::string relative = reference;
  std::replace(relative.begin(), relative.end(), '\\', '/');
  const fs::path resolved =
      fs::path(relative).is_absolute() ? fs::path(relative) : context.directory / relative;
  auto [it, inserted] = context.imageCache.try_emplace(resolved.string());
  if (inserted) {
    if (!regularFileExists(resolved)) {
      context.imageCache.erase(it);
      throwInputError("{}: texture '{}' of material '{}' not found (looked for {})", file,
                      reference, material, resolved.string());
    }
    try {
      it->second = readImage(resolved);
    } catch (const InputError& error) {
      context.imageCache.erase(it);
      throwInputError("{}: texture of material '{}': {}", file, material, error.what());
    }
  }
  return it->second;
}

glm::vec3 convertUp(const aiVector3D& v, bool zUp) {
  return zUp ? glm::vec3(v.x, v.z, -v.y) : glm::vec3(v.x, v.y, v.z);
}

// Union-find over vertex indices, joining vertices at the same position.
class Components {
 public:
  explicit Components(size_t n) : mParent(n) { std::iota(mParent.begin(), mParent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (mParent[x] != x) x = mParent[x] = mParent[mParent[x]];
    return x;
  }
  void join(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) mParent[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<uint32_t> mParent;
};

struct PositionKey {
  float x, y, z;
  bool operator==(const PositionKey&) const = default;
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    uint32_t bits[3];
    std::memcpy(bits, &k, sizeof bits);
    return (size_t(bits[0]) * 73856093u) ^ (size_t(bits[1]) * 19349663u) ^
           (size_t(bits[2]) * 83492791u);
  }
};

struct LeafFitStats {
  double maxPlaneDistance = 0.0;  // worst vertex distance from its leaf's plane, relative to size
  size_t degenerate = 0;          // components with no usable area, skipped
};

// Turns one connected leaf card (triangles over `vertices`) into a Leaf. The frame follows the
// texture parameterisation, so the quad's corners map to the uv rectangle as the file does.
bool fitLeaf(const std::vector<glm::vec3>& positions, const std::vector<glm::vec2>& uvs,
             const std::vector<uint32_t>& triangles, Leaf& leaf, LeafFitStats& stats) {
  glm::vec3 areaNormal(0.0f);
  float bestArea = 0.0f;
  size_t best = 0;
  for (size_t t = 0; t < triangles.size(); t += 3) {
    const glm::vec3 n = glm::cross(positions[triangles[t + 1]] - positions[triangles[t]],
                                   positions[triangles[t + 2]] - positions[triangles[t]]);
    areaNormal += n;
    if (glm::length(n) > bestArea) {
      bestArea = glm::length(n);
      best = t;
    }
  }
  if (bestArea <= 0.0f) return false;
  glm::vec3 normal =
      glm::length(areaNormal) > 0.1f * bestArea
          ? glm::normalize(areaNormal)
          : glm::normalize(glm::cross(positions[triangles[best + 1]] - positions[triangles[best]],
                                      positions[triangles[best + 2]] - positions[triangles[best]]));
  // Gradient of u and v on the largest triangle: dP/du and dP/dv.
  const glm::vec3 e1 = positions[triangles[best + 1]] - positions[triangles[best]];
  const glm::vec3 e2 = positions[triangles[best + 2]] - positions[triangles[best]];
  const glm::vec2 d1 = uvs[triangles[best + 1]] - uvs[triangles[best]];
  const glm::vec2 d2 = uvs[triangles[best + 2]] - uvs[triangles[best]];
  const float det = d1.x * d2.y - d1.y * d2.x;
  glm::vec3 axisU, axisV;
  if (std::abs(det) > 1e-12f) {
    const glm::vec3 dPdu = (e1 * d2.y - e2 * d1.y) / det;
    axisU = dPdu - normal * glm::dot(dPdu, normal);
  } else {
    axisU = e1;  // no usable uv: any in-plane axis
  }
  if (glm::length(axisU) < 1e-12f) return false;
  axisU = glm::normalize(axisU);
  axisV = glm::normalize(glm::cross(normal, axisU));
  if (std::abs(det) > 1e-12f) {
    const glm::vec3 dPdv = (e2 * d1.x - e1 * d2.x) / det;
    if (glm::dot(dPdv, axisV) < 0.0f) {  // mirrored mapping: the front is the other side
      axisV = -axisV;
      normal = -normal;
    }
  }
  glm::vec3 centroid(0.0f);
  for (uint32_t i : triangles) centroid += positions[i];
  centroid /= float(triangles.size());
  glm::vec2 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  glm::vec2 uvLo = lo, uvHi = hi;
  float planeDistance = 0.0f;
  for (uint32_t i : triangles) {
    const glm::vec3 d = positions[i] - centroid;
    const glm::vec2 p(glm::dot(d, axisU), glm::dot(d, axisV));
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
    uvLo = glm::min(uvLo, uvs[i]);
    uvHi = glm::max(uvHi, uvs[i]);
    planeDistance = std::max(planeDistance, std::abs(glm::dot(d, normal)));
  }
  const glm::vec2 half = (hi - lo) * 0.5f;
  if (half.x <= 0.0f || half.y <= 0.0f) return false;
  stats.maxPlaneDistance =
      std::max(stats.maxPlaneDistance, double(planeDistance / std::max(half.x, half.y)));
  leaf.normal = normal;
  leaf.axisU = axisU;
  leaf.axisV = axisV;
  leaf.center = centroid + axisU * (lo.x + half.x) + axisV * (lo.y + half.y);
  leaf.halfExtents = half;
  leaf.uvMin = uvLo;
  leaf.uvMax = uvHi;
  return true;
}

void addLeaves(const aiMesh& mesh, uint32_t textureId, bool zUp, Tree& tree, LeafFitStats& stats) {
  std::vector<glm::vec3> positions(mesh.mNumVertices);
  std::vector<glm::vec2> uvs(mesh.mNumVertices, glm::vec2(0.0f));
  for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
    positions[i] = convertUp(mesh.mVertices[i], zUp);
    if (mesh.HasTextureCoords(0))
      uvs[i] = {mesh.mTextureCoords[0][i].x, mesh.mTextureCoords[0][i].y};
  }
  Components components(mesh.mNumVertices);
  std::unordered_map<PositionKey, uint32_t, PositionHash> firstAt;
  for (uint32_t i = 0; i < mesh.mNumVertices; ++i) {
    auto [it, inserted] =
        firstAt.try_emplace(PositionKey{positions[i].x, positions[i].y, positions[i].z}, i);
    if (!inserted) components.join(i, it->second);
  }
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    for (unsigned k = 1; k < face.mNumIndices; ++k)
      components.join(face.mIndices[0], face.mIndices[k]);
  }
  // Triangles grouped by component, components in order of first appearance (deterministic).
  std::unordered_map<uint32_t, size_t> slot;
  std::vector<std::vector<uint32_t>> groups;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    const uint32_t root = components.find(face.mIndices[0]);
    auto [it, inserted] = slot.try_emplace(root, groups.size());
    if (inserted) groups.emplace_back();
    groups[it->second].insert(groups[it->second].end(), face.mIndices, face.mIndices + 3);
  }
  for (const auto& triangles : groups) {
    Leaf leaf;
    if (!fitLeaf(positions, uvs, triangles, leaf, stats)) {
      ++stats.degenerate;
      continue;
    }
    leaf.texture = textureId;
    tree.leaves.push_back(leaf);
  }
}

void addWood(const aiMesh& mesh, uint16_t materialId, bool zUp, WoodMesh& wood) {
  const auto base = static_cast<uint32_t>(wood.positions.size());
  for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
    wood.positions.push_back(convertUp(mesh.mVertices[i], zUp));
    glm::vec3 n = mesh.HasNormals() ? convertUp(mesh.mNormals[i], zUp) : glm::vec3(0, 1, 0);
    wood.normals.push_back(glm::length(n) > 0.0f ? glm::normalize(n) : glm::vec3(0, 1, 0));
    wood.uvs.push_back(mesh.HasTextureCoords(0)
                           ? glm::vec2(mesh.mTextureCoords[0][i].x, mesh.mTextureCoords[0][i].y)
                           : glm::vec2(0.0f));
  }
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    for (int k = 0; k < 3; ++k) wood.indices.push_back(base + face.mIndices[k]);
    wood.materialIds.push_back(materialId);
  }
}

void checkFinite(const aiMesh& mesh, const std::string& file) {
  for (unsigned i = 0; i < mesh.mNumVertices; ++i) {
    const aiVector3D& v = mesh.mVertices[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
      throwInputError("{}: mesh '{}' vertex {} is not finite ({}, {}, {})", file,
                      mesh.mName.C_Str(), i, v.x, v.y, v.z);
    }
  }
}

// Leaf images of a material: colour from the diffuse/base-colour texture, alpha from the
// opacity texture when there is a separate one (its alpha channel, or its red channel).
LeafTexture leafTextureOf(LoadContext& context, const aiMaterial& material) {
  const std::string name = materialName(material);
  std::string colorPath = texturePath(material, aiTextureType_DIFFUSE);
  if (colorPath.empty()) colorPath = texturePath(material, aiTextureType_BASE_COLOR);
  if (colorPath.empty()) {
    throwInputError("{}: leaf material '{}' has no colour texture", context.options.path, name);
  }
  LeafTexture texture;
  texture.name = name;
  texture.front = loadTexture(context, colorPath, name);
  const std::string opacityPath = texturePath(material, aiTextureType_OPACITY);
  if (!opacityPath.empty() && opacityPath != colorPath) {
    const ImageRgba8& opacity = loadTexture(context, opacityPath, name);
    if (opacity.width != texture.front.width || opacity.height != texture.front.height) {
      throwInputError(
          "{}: leaf material '{}': opacity texture size {}x{} differs from colour {}x{}",
          context.options.path, name, opacity.width, opacity.height, texture.front.width,
          texture.front.height);
    }
    bool opacityHasAlpha = false;
    for (size_t i = 3; i < opacity.pixels.size() && !opacityHasAlpha; i += 4)
      opacityHasAlpha = opacity.pixels[i] != 255;
    for (size_t i = 0; i < opacity.pixels.size(); i += 4) {
      texture.front.pixels[i + 3] = opacityHasAlpha ? opacity.pixels[i + 3] : opacity.pixels[i];
    }
  }
  texture.back = texture.front;
  const std::string normalPath = texturePath(material, aiTextureType_NORMALS);
  if (!normalPath.empty()) texture.normalMap = loadTexture(context, normalPath, name);
  return texture;
}

// Assimp loads an OBJ whose material library is missing as if it had no materials, and the
// leaves are then reported as untextured; name the missing library instead.
void checkObjMaterialLibraries(const fs::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension != ".obj") return;
  std::ifstream in(file, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("mtllib", 0) != 0 || line.size() < 7 || !std::isspace(uint8_t(line[6])))
      continue;
    std::string names = line.substr(7);
    while (!names.empty() && std::isspace(uint8_t(names.back()))) names.pop_back();
    names.erase(0, names.find_first_not_of(" \t"));
    if (names.empty() || regularFileExists(file.parent_path() / names)) continue;
    std::istringstream words(names);  // several libraries on one line
    for (std::string name; words >> name;) {
      if (!regularFileExists(file.parent_path() / name)) {
        throwInputError("{}: material library '{}' not found (looked for {})", file.string(), name,
                        (file.parent_path() / name).string());
      }
    }
  }
}

}  // namespace

Tree loadTreeFile(const TreeFileOptions& options) {
  const std::string& file = options.path;
  if (options.up != "y" && options.up != "z") {
    throwInputError(R"({}: up axis '{}' must be "y" or "z")", file, options.up);
  }
  if (!regularFileExists(file)) throwInputError("{}: file does not exist", file);
  std::error_code sizeError;
  if (fs::file_size(file, sizeError) == 0 || sizeError)
    throwInputError("{}: file is empty or unreadable", file);
  checkObjMaterialLibraries(file);
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      file, aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_GenSmoothNormals |
                aiProcess_JoinIdenticalVertices | aiProcess_FlipUVs | aiProcess_SortByPType |
                aiProcess_ValidateDataStructure);
  if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode) {
    throwInputError("{}: cannot load model ({})", file, importer.GetErrorString());
  }
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) checkFinite(*scene->mMeshes[m], file);

  // Which materials are leaves.
  std::vector<bool> isLeaf(scene->mNumMaterials, false);
  for (const std::string& wanted : options.leafMaterials) {
    bool found = false;
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
      if (materialName(*scene->mMaterials[m]) == wanted) isLeaf[m] = found = true;
    }
    if (!found)
      throwInputError("{}: leaf_materials names '{}', which the file does not have", file, wanted);
  }
  if (options.leafMaterials.empty()) {
    for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
      const aiMaterial& material = *scene->mMaterials[m];
      isLeaf[m] = isLeafMaterialName(materialName(material)) ||
                  !texturePath(material, aiTextureType_OPACITY).empty() || hasAlphaMode(material);
    }
  }

  LoadContext context{options, *scene, fs::path(file).parent_path(), {}};
  Tree tree;
  tree.name = fs::path(file).stem().string();
  const bool zUp = options.up == "z";
  std::map<unsigned, uint32_t> leafTextureOfMaterial;
  std::map<unsigned, uint16_t> woodMaterialOf;
  LeafFitStats stats;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const unsigned materialIndex = mesh.mMaterialIndex;
    const aiMaterial& material = *scene->mMaterials[materialIndex];
    if (isLeaf[materialIndex]) {
      auto [it, inserted] =
          leafTextureOfMaterial.try_emplace(materialIndex, uint32_t(tree.leafTextures.size()));
      if (inserted) tree.leafTextures.push_back(leafTextureOf(context, material));
      addLeaves(mesh, it->second, zUp, tree, stats);
    } else {
      auto [it, inserted] =
          woodMaterialOf.try_emplace(materialIndex, uint16_t(tree.woodMaterials.size()));
      if (inserted) {
        WoodMaterial wood;
        wood.name = materialName(material);
        aiColor4D diffuse(1, 1, 1, 1);
        material.Get(AI_MATKEY_COLOR_DIFFUSE, diffuse);
        // Material colours are linear factors; stored sRGB-encoded like textures.
        wood.baseColor = glm::vec4(linearToSrgb(diffuse.r), linearToSrgb(diffuse.g),
                                   linearToSrgb(diffuse.b), 1.0f);
        const std::string path = texturePath(material, aiTextureType_DIFFUSE);
        if (!path.empty()) {
          wood.texture = static_cast<int>(tree.woodTextures.size());
          tree.woodTextures.push_back(loadTexture(context, path, wood.name));
        }
        tree.woodMaterials.push_back(wood);
      }
      addWood(mesh, it->second, zUp, tree.wood);
    }
  }
  if (tree.leaves.empty() && stats.degenerate > 0) {
    throwInputError("{}: all {} leaf cards have zero area (nothing to draw)", file,
                    stats.degenerate);
  }
  if (tree.leaves.empty()) {
    std::string names;
    for (unsigned m = 0; m < scene->mNumMaterials; ++m)
      names += (names.empty() ? "'" : ", '") + materialName(*scene->mMaterials[m]) + "'";
    throwInputError("{}: no leaves found (materials: {}); name them with leaf_materials", file,
                    names);
  }
  if (stats.degenerate > 0)
    spdlog::warn("{}: skipped {} degenerate leaf cards", file, stats.degenerate);
  if (stats.maxPlaneDistance > 0.05) {
    spdlog::warn(
        "{}: some leaf cards are not planar (worst vertex {:.0f}% of the card size off its "
        "plane); they are drawn as flat quads",
        file, 100.0 * stats.maxPlaneDistance);
  }
  finalizeTree(tree, file);
  return tree;
}

}  // namespace canopy
