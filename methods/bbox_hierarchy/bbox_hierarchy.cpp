#include "methods/bbox_hierarchy/bbox_hierarchy.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>

#include "common/config.h"
#include "common/gl/ledger.h"
#include "methods/bbox_hierarchy/box_hierarchy.h"
#include "methods/common/leaf_capture.h"
#include "methods/common/lod_instances.h"
#include "methods/common/mesh.h"
#include "methods/common/mipmaps.h"

namespace canopy {
namespace {

// Each field is documented where visit() names it: that text is what --list-methods and
// docs/METHODS.md show.
struct BboxParams {
  int textureSize = 64;
  float volumeRatio = 0.1f;
  std::string arrangement = "cross";
  float transition = 0.25f;
  std::string hierarchy = "auto";
  int minBoxLeaves = 64;
  int spatialLeaves = 200;
  int supersample = 4;
  std::string compression = "none";
  float textureBudgetMb = 2.0f;
  std::string quadBlend = "facing";
  float facingPower = 1.0f;
  float lodBias = 1.0f;
  WoodParams wood;
  bool woodCapture = false;

  template <class Visitor>
  void visit(Visitor& v) {
    v("texture_size", textureSize, 8, 1024,
      "texels per side of every box image, all levels (§3.2.3: 64 or 128)");
    v("volume_ratio", volumeRatio, 0.0f, 1.0f,
      "no images for a box below this fraction of its parent's volume (§3.2.4)");
    v("arrangement", arrangement, {"cross", "diagonal"},
      "the six quads of a box: through its centre (Fig. 3) or on its diagonals (Fig. 6)");
    v("transition", transition, 0.0f, 10.0f,
      "blend band beyond a box's LoD distance, as a fraction of it (0: pop)");
    v("hierarchy", hierarchy, {"auto", "branches", "wood", "spatial"},
      "boxes from the L-system's branches, the wood mesh, or a spatial split of the leaves");
    v("min_box_leaves", minBoxLeaves, 1, 1000000,
      "no images for boxes holding fewer leaves (drawn as polygons: few leaves cost no more "
      "than a box's three image quads and look like the reference)");
    v("spatial_leaves", spatialLeaves, 1, 1000000,
      "spatial hierarchy: at most this many leaves per finest box");
    v("supersample", supersample, 1, 8, "capture samples per texel side");
    v("compression", compression, {"none", "dxt1", "dxt5"},
      "the box images: uncompressed, BC1 or BC3 (S3TC; four times the boxes in the same "
      "texture_budget_mb, but decoded in software on CPU renderers)");
    v("texture_budget_mb", textureBudgetMb, 0.0f, 100000.0f,
      "box images, as stored with their mip levels, within this many MB: the finest boxes "
      "(fewest leaves first) lose theirs, so the memory does not grow with the tree (the root "
      "keeps its images; the memory knob); 0: no bound");
    v("quad_blend", quadBlend, {"facing", "none"},
      "a box's seen quads: alpha-blended by how squarely each faces the viewer (§4; "
      "screen-door, order-independent: a quad keeps w / w_max of its pixels, w = "
      "|n·v|^facing_power) or all alpha-tested over each other");
    v("facing_power", facingPower, 0.25f, 16.0f,
      "quad_blend facing: sharpness of the weights (large: the most squarely facing quad only)");
    v("lod_bias", lodBias, 0.25f, 16.0f,
      "output pixels one box texel may span when the box is drawn as images (Fig. 5: 1); "
      "larger switches to images nearer the viewer: faster, coarser");
    wood.visit(v);
    v("wood_capture", woodCapture,
      "beyond the paper: the root box's images also hold the wood (opaque, its albedo), and a "
      "tree drawn with the root box alone draws no wood geometry: faster forests, but the "
      "crossed planes double the flattened branches (false: every tree draws its wood, as the "
      "paper; false in effect without wood)");
  }
};

// The asset header's own part: the hierarchy (nodes as the walk needs them) and its LoD data.
struct NodeFields {
  int32_t parent = -1;
  std::vector<int32_t> children;
  int level = 0;
  Aabb box;
  std::array<uint32_t, 3> leaves{};  // leafBegin, leafEnd, subtreeLeafEnd
  bool textured = false;
  template <class V>
  void visit(V& v) {
    v("parent", parent);
    v("children", children);
    v("level", level);
    v("box", box);
    v("leaves", leaves);
    v("textured", textured);
  }
};

struct AssetFields {
  std::vector<NodeFields> nodes;
  std::string source;  // where the boxes came from (branches, wood, spatial)
  std::vector<int32_t> texturedOrder;
  std::vector<uint32_t> boxFirstIndex;
  std::vector<float> worldPerTexel;
  uint32_t leafFirstIndex = 0;
  size_t leafImages = 0;
  float rootOnlyBelowPixels = 0.0f;  // wood_capture: trees below this draw the root box alone
  Aabb treeBounds;                   // their projected radius is the tree's bounding radius
  template <class V>
  void visit(V& v) {
    v("nodes", nodes);
    v("source", source);
    v("textured_order", texturedOrder);
    v("box_first_index", boxFirstIndex);
    v("world_per_texel", worldPerTexel);
    v("leaf_first_index", leafFirstIndex);
    v("leaf_images", leafImages);
    v("root_only_below_px", rootOnlyBelowPixels);
    v("tree_bounds", treeBounds);
  }
};

// The six quads of a box (§4, Fig. 3): planes through the box centre, each facing one way and
// showing the leaves seen from that side. "diagonal" (Fig. 6) turns the two vertical pairs onto
// the box's vertical diagonal planes; the horizontal pair stays.
std::array<Billboard, 6> boxQuads(const Aabb& box, bool diagonal) {
  const glm::vec3 c = box.center(), h = box.extent() * 0.5f;
  std::array<Billboard, 6> quads;
  const auto make = [&](glm::vec3 normal, glm::vec3 axisU, glm::vec2 half) {
    Billboard q;
    q.center = c;
    q.normal = normal;
    q.axisU = axisU;
    q.axisV = glm::cross(normal, axisU);
    q.halfExtents = half;
    return q;
  };
  if (!diagonal) {
    quads[0] = make({1, 0, 0}, {0, 0, -1}, {h.z, h.y});
    quads[1] = make({-1, 0, 0}, {0, 0, 1}, {h.z, h.y});
    quads[2] = make({0, 0, 1}, {1, 0, 0}, {h.x, h.y});
    quads[3] = make({0, 0, -1}, {-1, 0, 0}, {h.x, h.y});
  } else {
    const float diagonalHalf = std::sqrt(h.x * h.x + h.z * h.z);
    const glm::vec3 d1 = glm::normalize(glm::vec3(h.x, 0, h.z)),
                    d2 = glm::normalize(glm::vec3(h.x, 0, -h.z));
    const glm::vec3 n1 = glm::cross(glm::vec3(0, 1, 0), d1),
                    n2 = glm::cross(glm::vec3(0, 1, 0), d2);
    quads[0] = make(n1, -d1, {diagonalHalf, h.y});
    quads[1] = make(-n1, d1, {diagonalHalf, h.y});
    quads[2] = make(n2, -d2, {diagonalHalf, h.y});
    quads[3] = make(-n2, d2, {diagonalHalf, h.y});
  }
  quads[4] = make({0, 1, 0}, {1, 0, 0}, {h.x, h.z});
  quads[5] = make({0, -1, 0}, {-1, 0, 0}, {h.x, h.z});
  for (Billboard& q : quads) q.axisV = glm::cross(q.normal, q.axisU);
  return quads;
}

constexpr int kAtlasPadding = 4, kAtlasAlignment = 8;  // of the box image atlas

class BboxHierarchy final : public Method {
 public:
  explicit BboxHierarchy(BboxParams params) : mParams(std::move(params)) {
    if (!mParams.wood.draw) mParams.woodCapture = false;
  }

  void bake(const Tree& tree, BakeContext&) override {
    const bool hasBranches = !tree.branches.empty();
    if (mParams.hierarchy == "branches" && !hasBranches) {
      throwInputError(
          "bbox_hierarchy: parameter 'hierarchy' = \"branches\", but tree '{}' has no branch "
          "hierarchy",
          tree.name);
    }
    // auto: the L-system's boxes, else boxes derived from the wood, else a spatial hierarchy.
    mHierarchy = {};
    if (mParams.hierarchy == "branches" || (mParams.hierarchy == "auto" && hasBranches)) {
      mHierarchy = hierarchyFromBranches(tree);
    } else if (mParams.hierarchy != "spatial") {
      mHierarchy = woodHierarchy(tree);
      if (mHierarchy.nodes.empty() && mParams.hierarchy == "wood") {
        throwInputError(
            "bbox_hierarchy: parameter 'hierarchy' = \"wood\", but the wood of '{}' has fewer than "
            "two parts",
            tree.name);
      }
    }
    if (mHierarchy.nodes.empty()) mHierarchy = spatialHierarchy(tree, mParams.spatialLeaves);
    pruneByVolumeRatio(mHierarchy, mParams.volumeRatio,
                       static_cast<uint32_t>(mParams.minBoxLeaves));
    const size_t droppedByBudget = applyTextureBudget();
    // Six images per textured box (§3.2.2): the leaves of its subtree, orthographically, coarse
    // to fine in the atlas (§1, §6: progressive transmission).
    const LeafImageSampler sampler(tree);
    const std::vector<int32_t> textured = texturedCoarseToFine(mHierarchy);
    // wood_capture: the root's images hold every wood triangle; trees drawn with the root box
    // alone then draw an empty residual chain of the wood.
    const bool captureWood = mParams.woodCapture && tree.wood.triangleCount() > 0 &&
                             !textured.empty() && textured.front() == 0;
    std::optional<WoodColorSampler> woodSampler;
    std::vector<uint32_t> woodTriangles;
    if (captureWood) {
      woodSampler.emplace(tree);
      woodTriangles.resize(tree.wood.triangleCount());
      std::iota(woodTriangles.begin(), woodTriangles.end(), 0u);
    }
    std::vector<ImageRgba8> images(textured.size() * 6);
    std::vector<std::array<Billboard, 6>> quads(textured.size());
    tbb::parallel_for(size_t(0), textured.size(), [&](size_t t) {
      const BoxNode& node = mHierarchy.nodes[textured[t]];
      std::vector<uint32_t> leaves(mHierarchy.leafOrder.begin() + node.leafBegin,
                                   mHierarchy.leafOrder.begin() + node.subtreeLeafEnd);
      quads[t] = boxQuads(node.box, mParams.arrangement == "diagonal");
      const bool withWood = captureWood && textured[t] == 0;
      for (int f = 0; f < 6; ++f) {
        images[t * 6 + f] = captureLeavesOrthographic(
            tree, sampler, leaves, quads[t][f], mParams.textureSize, mParams.textureSize,
            mParams.supersample, false, withWood ? &*woodSampler : nullptr,
            withWood ? woodTriangles : std::vector<uint32_t>{});
      }
    });
    const ImageAtlas atlas = composeAtlas(images, kAtlasPadding, kAtlasAlignment);
    mAtlas = atlas.image;
    // Geometry: box quads (24 vertices each box), then one quad per leaf in hierarchy order.
    mVertices.clear();
    mIndices.clear();
    mBoxFirstIndex.assign(mHierarchy.nodes.size(), UINT32_MAX);
    mWorldPerTexel.assign(mHierarchy.nodes.size(), 0.0f);
    for (size_t t = 0; t < textured.size(); ++t) {
      const int32_t n = textured[t];
      mBoxFirstIndex[n] = static_cast<uint32_t>(mIndices.size());
      for (int f = 0; f < 6; ++f) {
        const Billboard& q = quads[t][f];
        const auto base = static_cast<uint32_t>(mVertices.size());
        for (int c = 0; c < 4; ++c)
          mVertices.push_back({q.corner(c), q.normal, atlas.cornerUv(t * 6 + f, c)});
        for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
        // §4, Fig. 5: the image shows one texel per pixel at distance size / texels · focal.
        mWorldPerTexel[n] =
            std::max(mWorldPerTexel[n],
                     2.0f * std::max(q.halfExtents.x, q.halfExtents.y) / mParams.textureSize);
      }
    }
    // The root box alone is drawn where the walk would choose it (the viewer beyond its LoD
    // distance and the transition band), measured as the wood measures its levels: the tree's
    // projected bounding radius, below radius · lod_bias / (root texel size · (1 + transition)).
    mTreeBounds = tree.bounds;
    mRootOnlyBelowPixels = 0.0f;
    std::vector<CapturedWood> capturedWood;
    if (captureWood) {
      mRootOnlyBelowPixels =
          treeRadius() * mParams.lodBias / (mWorldPerTexel[0] * (1.0f + mParams.transition));
      capturedWood.push_back(
          {std::vector<bool>(tree.wood.triangleCount(), true), mRootOnlyBelowPixels});
    }
    mWood.bake(tree, mParams.wood.levels(), capturedWood);
    mLeafFirstIndex = static_cast<uint32_t>(mIndices.size());
    for (uint32_t leafIndex : mHierarchy.leafOrder) {
      const Leaf& leaf = tree.leaves[leafIndex];
      const auto base = static_cast<uint32_t>(mVertices.size());
      for (int c = 0; c < 4; ++c) {
        glm::vec2 uv = leaf.cornerUv(c);
        uv.x += 2.0f * float(leaf.texture);  // the shader reads the texture index from uv.x
        mVertices.push_back({leaf.corner(c), leaf.normal, uv});
      }
      for (uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) mIndices.push_back(base + k);
    }
    mLeafImages.clear();
    for (const LeafTexture& t : tree.leafTextures) {
      if (t.front.width != tree.leafTextures[0].front.width ||
          t.front.height != tree.leafTextures[0].front.height) {
        throwInputError(
            "bbox_hierarchy: leaf textures of different sizes in '{}' are not supported",
            tree.name);
      }
      mLeafImages.push_back(t.front);
      mLeafImages.push_back(
          t.back.width == t.front.width && t.back.height == t.front.height ? t.back : t.front);
    }
    // Report: textured boxes and their texels' GPU bytes per level (§3.2.4; level 0 of the mip
    // chains, without the atlas padding).
    std::map<int32_t, std::pair<int, uint64_t>> perLevel;
    for (int32_t n : textured) {
      auto& [boxes, bytes] = perLevel[mHierarchy.nodes[n].level];
      ++boxes;
      bytes += 6 * boxImageBytes(mParams.textureSize, mParams.textureSize);
    }
    nlohmann::json levels = nlohmann::json::array();
    for (const auto& [level, value] : perLevel)
      levels.push_back(
          {{"level", level}, {"textured_boxes", value.first}, {"texel_bytes", value.second}});
    mReport = {
        {"hierarchy", mHierarchy.source},
        {"boxes", mHierarchy.nodes.size()},
        {"textured_boxes", textured.size()},
        {"boxes_over_texture_budget", droppedByBudget},
        {"levels", levels},
        {"atlas", {atlas.layout.width, atlas.layout.height}},
        {"wood_captured",
         {{"triangles", woodTriangles.size()}, {"root_only_below_px", mRootOnlyBelowPixels}}}};
    mTextured = textured;
  }

  void upload(gl::Device& device) override {
    using gl::MemoryCategory;
    mVbo = device.createBuffer(MemoryCategory::kGeometry, GL_ARRAY_BUFFER, mVertices,
                               "box quads and leaves");
    mIbo = device.createBuffer(MemoryCategory::kGeometry, GL_ELEMENT_ARRAY_BUFFER, mIndices,
                               "box and leaf indices");
    mVao = makeMeshVertexArray(mVbo, mIbo);
    mAtlasTexture = uploadAlphaTestedTexture(device, mAtlas, true, "box images",
                                             parseCompression(mParams.compression),
                                             CoverageTarget::kLevelZeroTest);
    const ImageRgba8& first = mLeafImages.front();
    mLeafTexture = device.createTexture({GL_TEXTURE_2D_ARRAY, first.width, first.height,
                                         static_cast<int>(mLeafImages.size()), GL_SRGB8_ALPHA8,
                                         true, MemoryCategory::kTexture, "leaf images"});
    for (size_t layer = 0; layer < mLeafImages.size(); ++layer) {
      device.uploadTextureLayer(mLeafTexture, static_cast<int>(layer), GL_RGBA, GL_UNSIGNED_BYTE,
                                mLeafImages[layer].pixels.data());
    }
    device.generateMipmaps(mLeafTexture);
    gl::setTextureSampling(mLeafTexture, true, false);
    // Every box's three quad pairs for the facing blend (the boxes' images face these ways).
    mPairNormals.assign(mHierarchy.nodes.size(), glm::mat3(1.0f));
    for (size_t n = 0; n < mHierarchy.nodes.size(); ++n) {
      const auto quads = boxQuads(mHierarchy.nodes[n].box, mParams.arrangement == "diagonal");
      mPairNormals[n] = glm::mat3(quads[0].normal, quads[2].normal, quads[4].normal);
    }
    mProgram = device.createProgram({gl::embeddedShader("methods/bbox_hierarchy/box.vert"),
                                     gl::embeddedShader("methods/bbox_hierarchy/box.frag")});
    mDevice = &device;
    mFrameOwner = device.owner() + "/frame";
    if (mParams.wood.draw) mWood.upload(device, true);
  }

  void draw(const FrameContext& frame, std::span<const Instance> instances) override {
    if (instances.empty()) return;
    mWood.drawAround(mParams.wood, frame, instances, [&] { drawLeaves(frame, instances); });
  }

  // Everything but the wood (drawAround orders the two).
  void drawLeaves(const FrameContext& frame, std::span<const Instance> instances) {
    // A box switches to its images where one of its texels spans lod_bias output pixels: its LoD
    // distance is its world size per texel times the output focal length (in pixels) / lod_bias.
    std::vector<float> lodDistance(mHierarchy.nodes.size());
    for (size_t n = 0; n < lodDistance.size(); ++n)
      lodDistance[n] = mWorldPerTexel[n] * frame.lodFocalPixels / mParams.lodBias;
    std::vector<std::vector<glm::mat4>> boxLists(mHierarchy.nodes.size()),
        leafLists(mHierarchy.nodes.size());
    for (const Instance& instance : instances)
      collectInstance(instance, frame, lodDistance, boxLists, leafLists);
    // One buffer: box instances node by node, then leaf instances node by node.
    std::vector<glm::mat4> matrices;
    std::vector<std::pair<GLint, GLsizei>> boxRanges(boxLists.size()), leafRanges(leafLists.size());
    for (size_t n = 0; n < boxLists.size(); ++n) {
      boxRanges[n] = {static_cast<GLint>(matrices.size()),
                      static_cast<GLsizei>(boxLists[n].size())};
      matrices.insert(matrices.end(), boxLists[n].begin(), boxLists[n].end());
    }
    for (size_t n = 0; n < leafLists.size(); ++n) {
      leafRanges[n] = {static_cast<GLint>(matrices.size()),
                       static_cast<GLsizei>(leafLists[n].size())};
      matrices.insert(matrices.end(), leafLists[n].begin(), leafLists[n].end());
    }
    uploadMatrices(matrices);
    mSignature = 0xcbf29ce484222325ull;
    mLeafPolygonsDrawn = 0;
    for (size_t n = 0; n < boxLists.size(); ++n) {
      if (!boxLists[n].empty()) mSignature = fnv1aMix(fnv1aMix(mSignature, n), boxLists[n].size());
      const BoxNode& node = mHierarchy.nodes[n];
      mLeafPolygonsDrawn += uint64_t(node.leafEnd - node.leafBegin) * leafLists[n].size();
    }
    const gl::Api& g = gl::api();
    mProgram.use();
    setFrameUniforms(mProgram, frame);
    mProgram.set("uAtlas", 0);
    mProgram.set("uBinaryAlpha", mParams.compression == "dxt1" ? 1 : 0);
    mProgram.set("uLeafImages", 1);
    mProgram.set("uTwoSided",
                 mLeafImages.size() >= 2 && mLeafImages[0].pixels != mLeafImages[1].pixels ? 1 : 0);
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D, mAtlasTexture.id());
    g.ActiveTexture(GL_TEXTURE1);
    g.BindTexture(GL_TEXTURE_2D_ARRAY, mLeafTexture.id());
    g.ActiveTexture(GL_TEXTURE0);
    g.BindVertexArray(mVao.id());
    // Box quads with back-face culling: three of the six are seen (Fig. 3).
    mProgram.set("uLeafMode", 0);
    mProgram.set("uCameraPosition", frame.cameraPosition);
    mProgram.set("uFacingBlend", mParams.quadBlend == "facing" ? 1 : 0);
    mProgram.set("uFacingPower", mParams.facingPower);
    g.Enable(GL_CULL_FACE);
    g.CullFace(GL_BACK);
    for (size_t n = 0; n < boxRanges.size(); ++n) {
      if (boxRanges[n].second == 0) continue;
      mProgram.set("uPairNormals", mPairNormals[n]);
      mProgram.set("uBoxCenter", mHierarchy.nodes[n].box.center());
      bindInstanceMatrices(mMatrixBuffer.id(), 4, boxRanges[n].first);
      g.DrawElementsInstanced(GL_TRIANGLES, 36, GL_UNSIGNED_INT,
                              reinterpret_cast<const void*>(sizeof(uint32_t) * mBoxFirstIndex[n]),
                              boxRanges[n].second);
    }
    g.Disable(GL_CULL_FACE);
    mProgram.set("uLeafMode", 1);
    mProgram.set("uFacingBlend", 0);
    for (size_t n = 0; n < leafRanges.size(); ++n) {
      const BoxNode& node = mHierarchy.nodes[n];
      if (leafRanges[n].second == 0 || node.leafEnd == node.leafBegin) continue;
      bindInstanceMatrices(mMatrixBuffer.id(), 4, leafRanges[n].first);
      g.DrawElementsInstanced(
          GL_TRIANGLES, static_cast<GLsizei>((node.leafEnd - node.leafBegin) * 6), GL_UNSIGNED_INT,
          reinterpret_cast<const void*>(sizeof(uint32_t) * (mLeafFirstIndex + node.leafBegin * 6)),
          leafRanges[n].second);
    }
    g.BindVertexArray(0);
  }

  uint64_t lodSignature() const override { return fnv1aMix(mSignature, mWood.lodSignature()); }
  uint64_t leafPolygonsDrawn() const override { return mLeafPolygonsDrawn; }
  std::vector<uint64_t> woodInstancesPerLevel() const override { return mWood.instancesPerLevel(); }
  nlohmann::json effectiveParams() const override { return writeParams(mParams); }
  nlohmann::json bakeReport() const override { return mWood.withLevels(mReport); }

  void save(AssetFolder& asset) const override {
    asset.describe("bbox_hierarchy", effectiveParams(), mReport);
    AssetFields fields;
    for (const BoxNode& n : mHierarchy.nodes) {
      fields.nodes.push_back({n.parent,
                              n.children,
                              n.level,
                              n.box,
                              {n.leafBegin, n.leafEnd, n.subtreeLeafEnd},
                              n.textured});
    }
    fields.source = mHierarchy.source;
    fields.texturedOrder = mTextured;
    fields.boxFirstIndex = mBoxFirstIndex;
    fields.worldPerTexel = mWorldPerTexel;
    fields.leafFirstIndex = mLeafFirstIndex;
    fields.leafImages = mLeafImages.size();
    fields.rootOnlyBelowPixels = mRootOnlyBelowPixels;
    fields.treeBounds = mTreeBounds;
    asset.writeFields(fields);
    asset.writeBlob("vertices.bin", mVertices);
    asset.writeBlob("indices.bin", mIndices);
    asset.writeBlob("leaf_order.bin", mHierarchy.leafOrder);
    asset.writeImage("box_images.png", mAtlas);  // boxes in level order: coarse first (§6)
    asset.writeImages("leaf_{}.png", mLeafImages);
    mWood.save(asset);
    asset.writeHeader();
  }

  void load(AssetFolder& asset) override {
    mReport = asset.readHeaderOf("bbox_hierarchy");
    AssetFields fields;
    asset.readFields(fields);
    const std::string folder = asset.folder().string();
    mHierarchy = {};
    mHierarchy.source = fields.source;
    for (const NodeFields& n : fields.nodes) {
      BoxNode node;
      node.parent = n.parent;
      node.children = n.children;
      node.level = n.level;
      node.box = n.box;
      node.leafBegin = n.leaves[0];
      node.leafEnd = n.leaves[1];
      node.subtreeLeafEnd = n.leaves[2];
      node.textured = n.textured;
      mHierarchy.nodes.push_back(std::move(node));
    }
    mTextured = fields.texturedOrder;
    mBoxFirstIndex = fields.boxFirstIndex;
    mWorldPerTexel = fields.worldPerTexel;
    mLeafFirstIndex = fields.leafFirstIndex;
    mRootOnlyBelowPixels = fields.rootOnlyBelowPixels;
    mTreeBounds = fields.treeBounds;
    if (!std::isfinite(mRootOnlyBelowPixels) || mRootOnlyBelowPixels < 0.0f)
      throwInputError("{}: corrupt box hierarchy header (root_only_below_px)", folder);
    mVertices = asset.readBlobAs<MeshVertex>("vertices.bin");
    mIndices = asset.readBlobAs<uint32_t>("indices.bin");
    mHierarchy.leafOrder = asset.readBlobAs<uint32_t>("leaf_order.bin");
    mAtlas = asset.readImage("box_images.png");
    mLeafImages = asset.readImages("leaf_{}.png", fields.leafImages);
    for (uint32_t index : mIndices) {
      if (index >= mVertices.size()) throwInputError("{}: corrupt indices", folder);
    }
    validateNodes(folder);
    mWood.load(asset);
    asset.finishReading();
  }

 private:
  // GPU bytes of one w × h level of the box images as `compression` stores them (the ledger's
  // own count).
  uint64_t boxImageBytes(int width, int height) const {
    return gl::textureLevelBytes(srgbInternalFormat(parseCompression(mParams.compression)), width,
                                 height, 1);
  }

  // Drops the finest boxes' images until the atlas, packed as bake() packs it and stored with
  // its mip levels (a third more) in `compression`, fits `texture_budget_mb`. Returns how many
  // boxes lost their images.
  size_t applyTextureBudget() {
    const size_t candidates = texturedCoarseToFine(mHierarchy).size();
    if (mParams.textureBudgetMb <= 0.0f || candidates == 0) return 0;
    const auto bytes = [&](size_t boxes) {
      const std::vector<glm::ivec2> sizes(boxes * 6, glm::ivec2(mParams.textureSize));
      const AtlasLayout layout = packAtlas(sizes, kAtlasPadding, kAtlasAlignment);
      return double(boxImageBytes(layout.width, layout.height)) * 4.0 / 3.0;
    };
    const double budget = double(mParams.textureBudgetMb) * 1e6;
    // The largest count that fits (at least the root's box): packing grows with the count.
    size_t lo = 1, hi = candidates;
    while (lo < hi) {
      const size_t mid = (lo + hi + 1) / 2;
      if (bytes(mid) <= budget) {
        lo = mid;
      } else {
        hi = mid - 1;
      }
    }
    keepTexturedBoxes(mHierarchy, lo);
    return candidates - lo;
  }

  // Every index the walk and the draws follow, checked so a corrupt asset cannot read past a
  // buffer; InputError naming the folder.
  void validateNodes(const std::string& folder) const {
    const size_t nodes = mHierarchy.nodes.size(), leaves = mHierarchy.leafOrder.size();
    bool valid = nodes > 0 && mBoxFirstIndex.size() == nodes && mWorldPerTexel.size() == nodes &&
                 !mLeafImages.empty() && size_t(mLeafFirstIndex) + leaves * 6 <= mIndices.size();
    for (size_t n = 0; valid && n < nodes; ++n) {
      const BoxNode& node = mHierarchy.nodes[n];
      valid = node.leafBegin <= node.leafEnd && node.leafEnd <= node.subtreeLeafEnd &&
              node.subtreeLeafEnd <= leaves && node.parent < int32_t(nodes) &&
              (!node.textured || size_t(mBoxFirstIndex[n]) + 36 <= mIndices.size());
      for (int32_t child : node.children) valid = valid && child > 0 && size_t(child) < nodes;
    }
    if (!valid) throwInputError("{}: corrupt box hierarchy header", folder);
  }

  // The tree's bounding radius, as the wood's levels and the root-only test measure it.
  float treeRadius() const { return 0.5f * glm::length(mTreeBounds.extent()); }

  // Walks one instance's hierarchy (Fig. 4) from its viewer position and adds its matrix to the
  // lists of what it draws; the matrix's unused bottom row carries the entry's dissolve.
  void collectInstance(const Instance& instance, const FrameContext& frame,
                       const std::vector<float>& lodDistance,
                       std::vector<std::vector<glm::mat4>>& boxLists,
                       std::vector<std::vector<glm::mat4>>& leafLists) {
    const glm::mat4 model = instance.modelMatrix();
    const glm::vec3 viewer =
        glm::vec3(glm::affineInverse(model) * glm::vec4(frame.cameraPosition, 1.0f));
    if (mRootOnlyBelowPixels > 0.0f) {
      // The wood follows this test (its empty residual chain), so the root's images, which hold
      // the wood, are drawn whenever it passes, a forced level or not.
      const glm::vec3 centre = glm::vec3(model * glm::vec4(mTreeBounds.center(), 1.0f));
      if (frame.projectedPixels(treeRadius() * instance.scale,
                                glm::length(frame.cameraPosition - centre)) <
          mRootOnlyBelowPixels) {
        boxLists[0].push_back(model);
        return;
      }
    }
    walkHierarchy(mHierarchy, lodDistance, viewer, mParams.transition, frame.forcedLevel, mWalk);
    const auto withDissolve = [&](const WalkEntry& entry) {
      glm::mat4 m = model;
      m[0][3] = entry.threshold;
      m[1][3] = entry.keepBelow ? 1.0f : 0.0f;
      return m;
    };
    for (const WalkEntry& entry : mWalk.boxes) boxLists[entry.node].push_back(withDissolve(entry));
    for (const WalkEntry& entry : mWalk.leafNodes)
      leafLists[entry.node].push_back(withDissolve(entry));
  }

  void uploadMatrices(const std::vector<glm::mat4>& matrices) {
    if (matrices.size() > mMatrixCapacity || !mMatrixBuffer.id()) {
      mMatrixCapacity = std::max<size_t>(matrices.size() * 2, 64);
      gl::Device::OwnerScope owner(*mDevice, mFrameOwner);
      mMatrixBuffer = mDevice->createBuffer(
          gl::MemoryCategory::kOther, GL_ARRAY_BUFFER, mMatrixCapacity * sizeof(glm::mat4), nullptr,
          "per-frame box and leaf instance lists", GL_DYNAMIC_DRAW);
    }
    const gl::Api& g = gl::api();
    g.BindBuffer(GL_ARRAY_BUFFER, mMatrixBuffer.id());
    g.BufferSubData(GL_ARRAY_BUFFER, 0,
                    static_cast<GLsizeiptr>(matrices.size() * sizeof(glm::mat4)), matrices.data());
    g.BindBuffer(GL_ARRAY_BUFFER, 0);
  }

  BboxParams mParams;
  BoxHierarchy mHierarchy;
  std::vector<int32_t> mTextured;
  std::vector<uint32_t> mBoxFirstIndex;
  std::vector<float> mWorldPerTexel;
  HierarchyWalk mWalk;                  // one instance's walk, reused across instances
  std::vector<glm::mat3> mPairNormals;  // per node: its quad pairs' normals (facing blend)
  uint64_t mSignature = 0;          // of the boxes the last draw showed as images (popping metric)
  uint64_t mLeafPolygonsDrawn = 0;  // leaves the last draw drew as polygons, all instances
  uint32_t mLeafFirstIndex = 0;
  Aabb mTreeBounds;                   // the wood's and the root-only test's projected radius
  float mRootOnlyBelowPixels = 0.0f;  // wood_capture: trees below draw the root box alone
  std::vector<MeshVertex> mVertices;
  std::vector<uint32_t> mIndices;
  ImageRgba8 mAtlas;
  std::vector<ImageRgba8> mLeafImages;
  nlohmann::json mReport;
  gl::Buffer mVbo, mIbo, mMatrixBuffer;
  size_t mMatrixCapacity = 0;
  gl::VertexArray mVao;
  gl::Texture mAtlasTexture, mLeafTexture;
  gl::Program mProgram;
  gl::Device* mDevice = nullptr;
  std::string mFrameOwner;
  WoodRenderer mWood;
};

}  // namespace

void registerBboxHierarchy(MethodRegistry& registry) {
  addMethod<BboxHierarchy, BboxParams>(
      registry, "bbox_hierarchy",
      "bounding-box hierarchy of six images per box (Lluch et al. 2004)",
      {.memoryKnob = MemoryKnob{"texture_budget_mb", 0.05, 64.0, false, true},
       .cost = {.bakeSeconds = 1.8, .frameCost = 0.9}});
}

}  // namespace canopy
