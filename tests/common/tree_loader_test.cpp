#include "common/tree_loader.h"

#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "common/image.h"
#include "test_support.h"

namespace canopy {
namespace {

void writeLeafPng(const std::filesystem::path& path) {
  ImageRgba8 image(8, 8);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      uint8_t* p = image.at(x, y);
      p[0] = 40;
      p[1] = 160;
      p[2] = 30;
      p[3] = (x >= 2 && x < 6) ? 255 : 0;
    }
  }
  writePng(path, image);
}

// Blender's OBJ exporter: quads, a bark material with a colour, a leaf material with
// map_Kd/map_d. Three leaf quads of size 0.2 × 0.1 (u along x, v along y), one wood triangle.
constexpr const char* kBlenderMtl = R"(newmtl bark
Kd 0.300000 0.200000 0.100000
newmtl leaf
map_Kd leaf.png
map_d leaf.png
)";
constexpr const char* kBlenderObj = R"(mtllib tree.mtl
o tree
v 0 0 0
v 0.1 0 0
v 0 1 0
vt 0 0
vn 0 0 1
usemtl bark
f 1/1/1 2/1/1 3/1/1
o leaves
v 0 1 0
v 0.2 1 0
v 0.2 1.1 0
v 0 1.1 0
v 1 1 0
v 1.2 1 0
v 1.2 1.1 0
v 1 1.1 0
v 0 2 0
v 0.2 2 0
v 0.2 2.1 0
v 0 2.1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl leaf
f 4/2 5/3 6/4 7/5
f 8/2 9/3 10/4 11/5
f 12/2 13/3 14/4 15/5
)";

struct Fixture {
  test::TempDir dir;
  std::filesystem::path obj;
  Fixture(const std::string& mtl = kBlenderMtl, const std::string& objText = kBlenderObj,
          bool png = true) {
    obj = dir / "tree.obj";
    test::writeText(dir / "tree.mtl", mtl);
    test::writeText(obj, objText);
    if (png) writeLeafPng(dir / "leaf.png");
  }
};

TEST(TreeLoader, BlenderObjWithLeafTextures) {
  Fixture f;
  const Tree tree = loadTreeFile({f.obj.string()});
  ASSERT_EQ(tree.leaves.size(), 3u);
  EXPECT_EQ(tree.wood.triangleCount(), 1u);
  ASSERT_EQ(tree.leafTextures.size(), 1u);
  EXPECT_EQ(tree.leafTextures[0].front.width, 8);
  EXPECT_EQ(tree.leafTextures[0].front.at(0, 0)[3], 0);  // alpha from map_d
  EXPECT_EQ(tree.leafTextures[0].front.at(3, 3)[3], 255);
  for (const Leaf& leaf : tree.leaves) {
    EXPECT_NEAR(leaf.halfExtents.x, 0.1f, 1e-5f);
    EXPECT_NEAR(leaf.halfExtents.y, 0.05f, 1e-5f);
    EXPECT_NEAR(std::abs(leaf.normal.z), 1.0f, 1e-5f);
    EXPECT_NEAR(leaf.axisU.x, 1.0f, 1e-5f);  // u grows along +x in the file
    EXPECT_NEAR(leaf.uvMin.x, 0.0f, 1e-6f);
    EXPECT_NEAR(leaf.uvMax.x, 1.0f, 1e-6f);
  }
  // Corners land on the file's vertices: the first leaf spans x in [0, 0.2], y in [1, 1.1].
  const Leaf& first = tree.leaves[0];
  EXPECT_NEAR(first.center.x, 0.1f, 1e-5f);
  EXPECT_NEAR(first.center.y, 1.05f, 1e-5f);
  // The file's v = 0 edge (y = 1) is Canopy's v = 1 (v = 0 at the top image row).
  EXPECT_NEAR(glm::dot(first.axisV, glm::vec3(0, -1, 0)), 1.0f, 1e-5f);
  // Wood colour: Kd is linear, stored sRGB-encoded.
  EXPECT_NEAR(tree.woodMaterials[0].baseColor.r, linearToSrgb(0.3f), 1e-5f);
}

TEST(TreeLoader, ThreeJsObjWithUsemtlPerMeshAndTriangleCards) {
  // OBJExporter style: "o" + "usemtl" per mesh; each card two triangles over four vertices.
  const std::string mtl =
      "newmtl branches\nKd 1 1 1\nnewmtl leaves\nKd 1 1 1\nmap_Kd leaf.png\nmap_d leaf.png\n";
  const std::string obj = R"(mtllib tree.mtl
o branches
usemtl branches
v 0 0 0
v 0.2 0 0
v 0 2 0
f 1 2 3
o leaves
usemtl leaves
v 0 1 0
v 0 1 0.3
v 0 1.2 0.3
v 0 1.2 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
f 4/1 5/2 6/3
f 4/1 6/3 7/4
v 1 1 0
v 1 1 0.3
v 1 1.2 0.3
v 1 1.2 0
f 8/1 9/2 10/3
f 8/1 10/3 11/4
)";
  Fixture f(mtl, obj);
  const Tree tree = loadTreeFile({f.obj.string()});
  ASSERT_EQ(tree.leaves.size(), 2u);
  EXPECT_NEAR(std::abs(tree.leaves[0].normal.x), 1.0f, 1e-5f);
  EXPECT_NEAR(tree.leaves[0].halfExtents.x, 0.15f, 1e-5f);
  EXPECT_NEAR(tree.leaves[0].halfExtents.y, 0.1f, 1e-5f);
}

TEST(TreeLoader, LeafMaterialsOverrideAndZUp) {
  const std::string mtl = "newmtl stem\nKd 1 1 1\nnewmtl card\nmap_Kd leaf.png\n";
  std::string obj = kBlenderObj;
  obj.replace(obj.find("usemtl bark"), 11, "usemtl stem");
  obj.replace(obj.find("usemtl leaf"), 11, "usemtl card");
  Fixture f(mtl, obj);
  // "card" matches no rule and has no opacity map: without the override there are no leaves.
  try {
    loadTreeFile({f.obj.string()});
    FAIL() << "expected no leaves";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("no leaves"), std::string::npos);
  }
  TreeFileOptions options{f.obj.string(), {"card"}, "z"};
  const Tree tree = loadTreeFile(options);
  ASSERT_EQ(tree.leaves.size(), 3u);
  // Z-up file: the file's +y becomes −z, and its +z becomes +y.
  EXPECT_NEAR(tree.leaves[0].center.z, -1.05f, 1e-5f);
  EXPECT_NEAR(std::abs(tree.leaves[0].normal.y), 1.0f, 1e-5f);
  EXPECT_THROW(loadTreeFile({f.obj.string(), {"Nonexistent"}}), InputError);
}

std::string base64(const std::string& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t n = uint8_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= uint8_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= uint8_t(bytes[i + 2]);
    out += kTable[(n >> 18) & 63];
    out += kTable[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kTable[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kTable[n & 63] : '=';
  }
  return out;
}

// A PNG whose IHDR claims 60000 × 60000 RGBA pixels, followed by a few bytes of image data: a
// reader learns the size before it finds the data missing.
std::string hugePngHeader() {
  const auto bigEndian = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  const auto chunk = [&](const std::string& typeAndData) {
    uint32_t crc = 0xFFFFFFFFu;  // CRC-32 of the chunk type and data, as PNG requires
    for (unsigned char byte : typeAndData) {
      crc ^= byte;
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return bigEndian(uint32_t(typeAndData.size() - 4)) + typeAndData + bigEndian(~crc);
  };
  return std::string("\x89PNG\r\n\x1a\n", 8) +
         chunk("IHDR" + bigEndian(60000) + bigEndian(60000) + std::string("\x08\x06\0\0\0", 5)) +
         chunk("IDAT" + std::string("\x78\x01\x00\x00", 4)) + chunk("IEND");
}

// One leaf quad (positions, uvs, indices) as glTF; material named "Mat.001" (no leaf word) with
// alphaMode MASK, so the alpha rule must find it. The leaf texture is `png`, stored as the
// `placement` says: a file beside the model, a data URI, or (GLB) a buffer view of the binary
// chunk.
enum class ImagePlacement { kFile, kDataUri, kGlbBufferView };

std::string leafQuadGltfJson(const std::string& images, const std::string& buffers,
                             const std::string& extraBufferViews) {
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
  "indices": 2, "material": 0}]}],
  "materials": [{"name": "Mat.001", "alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
  "textures": [{"source": 0}], "images": [)" +
         images + R"(], "buffers": [)" + buffers + R"(],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                  {"buffer": 0, "byteOffset": 80, "byteLength": 12})" +
         extraBufferViews + R"(],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [0.4, 0.2, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]})";
}

// GLB container: 12-byte header, a JSON chunk padded with spaces, a BIN chunk padded with zeros.
std::string glbContainer(std::string json, std::string binary) {
  json.resize((json.size() + 3) / 4 * 4, ' ');
  binary.resize((binary.size() + 3) / 4 * 4, '\0');
  std::string out;
  const auto word = [&](uint32_t value) { out.append(reinterpret_cast<const char*>(&value), 4); };
  word(0x46546C67);  // "glTF"
  word(2);
  word(uint32_t(12 + 8 + json.size() + 8 + binary.size()));
  word(uint32_t(json.size()));
  word(0x4E4F534A);  // "JSON"
  out += json;
  word(uint32_t(binary.size()));
  word(0x004E4942);  // "BIN\0"
  out += binary;
  return out;
}

std::filesystem::path writeLeafQuadModel(const test::TempDir& dir, ImagePlacement placement) {
  const float positions[] = {0, 0, 0, 0.4f, 0, 0, 0.4f, 0.2f, 0, 0, 0.2f, 0};
  const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  std::string geometry(reinterpret_cast<const char*>(positions), sizeof positions);
  geometry.append(reinterpret_cast<const char*>(uvs), sizeof uvs);
  geometry.append(reinterpret_cast<const char*>(indices), sizeof indices);
  writeLeafPng(dir / "leaf.png");
  const std::string png = test::readText(dir / "leaf.png");
  const std::string dataBuffer =
      R"({"byteLength": 92, "uri": "data:application/octet-stream;base64,)" + base64(geometry) +
      R"("})";
  if (placement == ImagePlacement::kFile) {
    test::writeText(dir / "leaf.gltf", leafQuadGltfJson(R"({"uri": "leaf.png"})", dataBuffer, ""));
    return dir / "leaf.gltf";
  }
  std::filesystem::remove(dir / "leaf.png");  // the model must not find it beside itself
  if (placement == ImagePlacement::kDataUri) {
    const std::string image = R"({"uri": "data:image/png;base64,)" + base64(png) + R"("})";
    test::writeText(dir / "leaf.gltf", leafQuadGltfJson(image, dataBuffer, ""));
    return dir / "leaf.gltf";
  }
  const std::string binary = geometry + png;
  const std::string json = leafQuadGltfJson(
      R"({"bufferView": 3, "mimeType": "image/png"})",
      R"({"byteLength": )" + std::to_string(binary.size()) + "}",
      R"(, {"buffer": 0, "byteOffset": 92, "byteLength": )" + std::to_string(png.size()) + "}");
  test::writeText(dir / "leaf.glb", glbContainer(json, binary));
  return dir / "leaf.glb";
}

void expectOneLeafQuad(const std::filesystem::path& model) {
  const Tree tree = loadTreeFile({model.string()});
  ASSERT_EQ(tree.leaves.size(), 1u);
  EXPECT_NEAR(tree.leaves[0].halfExtents.x, 0.2f, 1e-5f);
  EXPECT_NEAR(tree.leaves[0].halfExtents.y, 0.1f, 1e-5f);
  ASSERT_EQ(tree.leafTextures[0].front.width, 8);
  // The texture's alpha survives (columns 2..5 opaque), wherever it was stored.
  EXPECT_EQ(tree.leafTextures[0].front.at(0, 4)[3], 0);
  EXPECT_EQ(tree.leafTextures[0].front.at(3, 4)[3], 255);
  // glTF's uv v = 0 is the top image row, as in Canopy: the quad's top edge (y = 0.2) has v = 0.
  EXPECT_NEAR(glm::dot(tree.leaves[0].axisV, glm::vec3(0, -1, 0)), 1.0f, 1e-5f);
}

TEST(TreeLoader, GltfWithAlphaMaskMaterial) {
  test::TempDir dir;
  expectOneLeafQuad(writeLeafQuadModel(dir, ImagePlacement::kFile));
}

// Downloaded assets usually carry their textures inside the file.
TEST(TreeLoader, GltfWithTextureInADataUri) {
  test::TempDir dir;
  expectOneLeafQuad(writeLeafQuadModel(dir, ImagePlacement::kDataUri));
}

TEST(TreeLoader, GlbWithTextureInItsBinaryChunk) {
  test::TempDir dir;
  expectOneLeafQuad(writeLeafQuadModel(dir, ImagePlacement::kGlbBufferView));
}

// Each bad input gives an InputError whose message names the file and the problem.
void expectInputError(const std::filesystem::path& file, const std::string& words) {
  try {
    loadTreeFile({file.string()});
    FAIL() << "expected an InputError for " << file;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(file.filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find(words), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
  }
}

TEST(TreeLoaderBadInput, MissingFile) {
  test::TempDir dir;
  expectInputError(dir / "absent.obj", "does not exist");
}

TEST(TreeLoaderBadInput, GarbageAndTruncatedFiles) {
  test::TempDir dir;
  test::writeText(dir / "garbage.glb", std::string("\x01\x02not a model at all\xff\xfe", 22));
  expectInputError(dir / "garbage.glb", "cannot load");
  test::writeText(dir / "cut.gltf", R"({"asset": {"version": "2.0"}, "meshes": [{"primitives": [)");
  expectInputError(dir / "cut.gltf", "cannot load");
  test::writeText(dir / "empty.obj", "");
  expectInputError(dir / "empty.obj", "empty");
}

TEST(TreeLoaderBadInput, MissingTexture) {
  Fixture f(kBlenderMtl, kBlenderObj, /*png=*/false);
  expectInputError(f.obj, "leaf.png");
}

TEST(TreeLoaderBadInput, TextureThatIsNotAnImage) {
  Fixture f(kBlenderMtl, kBlenderObj, /*png=*/false);
  test::writeText(f.dir / "leaf.png", "this is text, not a PNG");
  expectInputError(f.obj, "leaf.png");
}

TEST(TreeLoaderBadInput, NonFiniteVertex) {
  std::string obj = kBlenderObj;
  obj.replace(obj.find("v 0.2 1 0\n"), 10, "v nan 1 0\n");
  Fixture f(kBlenderMtl, obj);
  expectInputError(f.obj, "not finite");
}

TEST(TreeLoaderBadInput, ModelWithoutLeaves) {
  Fixture f("newmtl bark\nKd 1 1 1\n",
            "mtllib tree.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl bark\nf 1 2 3\n");
  expectInputError(f.obj, "no leaves");
}

TEST(TreeLoaderBadInput, MissingMaterialLibraryIsNamed) {
  Fixture f(kBlenderMtl, kBlenderObj);
  std::filesystem::remove(f.dir / "tree.mtl");
  expectInputError(f.obj, "material library 'tree.mtl' not found");
  // A name longer than the system allows (found by the tree_loader fuzz target: the existence
  // check threw filesystem_error) is a library that is not found, too.
  test::writeText(f.obj, "mtllib " + std::string(5000, 'm') + "\n" + kBlenderObj);
  expectInputError(f.obj, "not found");
}

TEST(TreeLoaderBadInput, LeavesOfZeroAreaAreNamedAsSuch) {
  std::string obj = kBlenderObj;
  // Every leaf quad collapsed onto a line (all y = 1, 1.1 → the same value).
  for (const char* from : {"1.1 0\n", "2.1 0\n"}) {
    for (size_t at; (at = obj.find(from)) != std::string::npos;)
      obj.replace(at, std::string(from).size(), std::string(from) == "1.1 0\n" ? "1 0\n" : "2 0\n");
  }
  Fixture f(kBlenderMtl, obj);
  expectInputError(f.obj, "zero area");
}

TEST(TreeLoaderBadInput, CorruptAndOversizedTexturesGiveOneLineAndPrintNothing) {
  Fixture f(kBlenderMtl, kBlenderObj);
  const std::string png = test::readText(f.dir / "leaf.png");
  // Truncated in the image data, and a header claiming 60000² pixels: libpng prints its own
  // "libpng error" line unless it is captured into our message.
  for (const std::string& bad : {png.substr(0, png.size() - 20), hugePngHeader()}) {
    test::writeText(f.dir / "leaf.png", bad);
    ::testing::internal::CaptureStderr();
    expectInputError(f.obj, "leaf.png");
    const std::string printed = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(printed, "") << "a library printed on its own";
  }
  test::writeText(f.dir / "leaf.png", hugePngHeader());
  expectInputError(f.obj, "60000×60000 pixels is larger than Canopy reads");
}

TEST(TreeLoader, LeafRuleMatchesCommonNames) {
  EXPECT_TRUE(isLeafMaterialName("Leaves"));
  EXPECT_TRUE(isLeafMaterialName("pine_NEEDLES"));
  EXPECT_TRUE(isLeafMaterialName("Foliage.001"));
  EXPECT_FALSE(isLeafMaterialName("bark"));
}

}  // namespace
}  // namespace canopy

#include "common/tree_export.h"

namespace canopy {
namespace {

TEST(TreeLoader, ExportedBuiltInTreeLoadsBackLeafForLeaf) {
  test::TempDir dir;
  Tree tree = test::smallTree(500);
  tree.name = "small";
  const auto path = exportTreeObj(tree, dir.path());
  const Tree loaded = loadTreeFile({path.string()});
  ASSERT_EQ(loaded.leaves.size(), tree.leaves.size());
  EXPECT_EQ(loaded.wood.triangleCount(), tree.wood.triangleCount());
  EXPECT_EQ(loaded.leafTextures.size(), tree.leafTextures.size());
  // Leaves come back in texture order; compare as sets of centres by matching each one.
  const float tolerance = 1e-4f * tree.boundingSphereRadius();
  size_t matched = 0;
  for (const Leaf& original : tree.leaves) {
    for (const Leaf& back : loaded.leaves) {
      if (glm::length(back.center - original.center) < tolerance) {
        EXPECT_NEAR(std::abs(glm::dot(back.normal, original.normal)), 1.0f, 1e-3f);
        EXPECT_NEAR(back.halfExtents.x, original.halfExtents.x, tolerance);
        EXPECT_NEAR(back.halfExtents.y, original.halfExtents.y, tolerance);
        ++matched;
        break;
      }
    }
  }
  EXPECT_EQ(matched, tree.leaves.size());
}

}  // namespace
}  // namespace canopy
