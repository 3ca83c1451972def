#include "common/lsystem.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "common/leaf_texture_gen.h"
#include "common/random.h"

namespace canopy {
namespace {

constexpr float kDegToRad = 3.14159265358979f / 180.0f;

// The apex production: an internode, a lateral apex in brackets (while the order allows), and
// the continuing apex rolled by the divergence angle.
void rewriteApex(const Module& apex, const LSystemTreeParams& params, Random& random,
                 std::vector<Module>& out) {
  const float length = apex.p[0], radius = apex.p[1];
  const int order = static_cast<int>(apex.p[2]);
  out.push_back(Module::make('F', length, radius, float(order)));
  if (order < params.maxOrder) {
    // Order-0 axes bear `trunkLaterals` laterals per internode, spread around; others bear one.
    const int laterals = order == 0 ? params.trunkLaterals : 1;
    for (int i = 0; i < laterals; ++i) {
      const float pitch = params.branchAngle + random.uniform(-1, 1) * params.angleJitter;
      out.push_back(Module::make('['));
      out.push_back(Module::make(
          '/', 360.0f * float(i) / float(laterals) + random.uniform(-1, 1) * params.angleJitter));
      out.push_back(Module::make('&', pitch));
      out.push_back(Module::make('A', length * params.lateralLengthRatio,
                                 radius * params.radiusRatio, float(order + 1)));
      out.push_back(Module::make(']'));
    }
  }
  out.push_back(Module::make('/', params.divergence + random.uniform(-1, 1) * params.angleJitter));
  // A small random turn keeps axes from being perfectly straight.
  out.push_back(Module::make('+', random.uniform(-1, 1) * params.angleJitter * 0.5f));
  out.push_back(Module::make('A', length * params.mainLengthRatio, radius * params.mainRadiusRatio,
                             float(order)));
}

// Distributes exactly params.leaves leaves along the segments of order >= leafOrder, in
// proportion to their length, as L modules placed after each segment (offset back along it).
std::vector<Module> distributeLeaves(const std::vector<Module>& modules,
                                     const LSystemTreeParams& params, Random& random) {
  double bearingLength = 0.0;
  for (const Module& m : modules) {
    if (m.symbol == 'F' && m.p[2] >= float(params.leafOrder)) bearingLength += m.p[0];
  }
  if (bearingLength <= 0.0) {
    throwInputError("preset '{}': no segment of order >= {} to carry leaves", params.preset,
                    params.leafOrder);
  }
  const double density = double(params.leaves) / bearingLength;
  std::vector<Module> out;
  out.reserve(modules.size() + size_t(params.leaves));
  double accumulated = 0.0;
  int placed = 0;
  for (const Module& m : modules) {
    out.push_back(m);
    if (m.symbol != 'F' || m.p[2] < float(params.leafOrder)) continue;
    accumulated += m.p[0] * density;
    const int target = std::min(params.leaves, static_cast<int>(std::lround(accumulated)));
    const int count = target - placed;
    for (int j = 0; j < count; ++j) {
      const float back = m.p[0] * (1.0f - (j + random.uniform()) / float(count));
      const float scale = 1.0f + random.uniform(-1, 1) * params.leafSizeJitter;
      const float pitch = params.leafPitch + random.uniform(-1, 1) * 20.0f;
      const float roll = float(placed + j) * 137.5f + random.uniform(-1, 1) * 25.0f;
      out.push_back(Module::make('L', scale, pitch, roll, back));
    }
    placed = target;
  }
  return out;
}

// Turtle state: position, orthonormal frame (heading, left, up = heading × left), branch node.
struct Turtle {
  glm::vec3 position{0.0f};
  glm::vec3 heading{0.0f, 1.0f, 0.0f};
  glm::vec3 left{-1.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 0.0f, 1.0f};
  int32_t node = 0;

  void rotate(glm::vec3& a, glm::vec3& b, float degrees) {
    const float c = std::cos(degrees * kDegToRad), s = std::sin(degrees * kDegToRad);
    const glm::vec3 na = a * c + b * s;
    const glm::vec3 nb = b * c - a * s;
    a = glm::normalize(na);
    b = glm::normalize(nb);
  }
  void turn(float degrees) { rotate(heading, left, degrees); }
  void pitch(float degrees) { rotate(heading, up, -degrees); }
  void roll(float degrees) { rotate(left, up, degrees); }

  // Bends the heading towards gravity (or away when strength < 0) and re-orthonormalises.
  void applyTropism(float strength) {
    if (strength == 0.0f) return;
    const glm::vec3 bent = heading + glm::vec3(0.0f, -strength, 0.0f);
    if (glm::length(bent) < 1e-4f) return;
    heading = glm::normalize(bent);
    left = glm::cross(up, heading);
    if (glm::length(left) < 1e-4f) left = glm::cross(glm::vec3(1, 0, 0), heading);
    left = glm::normalize(left);
    up = glm::normalize(glm::cross(heading, left));
  }
};

int sidesForRadius(float radius, float trunkRadius) {
  if (radius > 0.3f * trunkRadius) return 10;
  if (radius > 0.08f * trunkRadius) return 6;
  return 4;
}

void addCylinder(WoodMesh& wood, const Turtle& turtle, float length, float radius, float topRadius,
                 int sides, Aabb& nodeBounds) {
  const auto base = static_cast<uint32_t>(wood.positions.size());
  const glm::vec3 top = turtle.position + turtle.heading * length;
  for (int ring = 0; ring < 2; ++ring) {
    const glm::vec3 centre = ring == 0 ? turtle.position : top;
    const float r = ring == 0 ? radius : topRadius;
    for (int s = 0; s <= sides; ++s) {
      const float angle = 2.0f * 3.14159265358979f * float(s) / float(sides);
      const glm::vec3 radial = turtle.left * std::cos(angle) + turtle.up * std::sin(angle);
      const glm::vec3 p = centre + radial * r;
      wood.positions.push_back(p);
      wood.normals.push_back(glm::normalize(radial));
      wood.uvs.emplace_back(float(s) / float(sides), float(ring) * length);
      nodeBounds.extend(p);
    }
  }
  const auto stride = static_cast<uint32_t>(sides + 1);
  for (uint32_t s = 0; s < uint32_t(sides); ++s) {
    const uint32_t a = base + s, b = base + s + 1, c = base + stride + s + 1, d = base + stride + s;
    wood.indices.insert(wood.indices.end(), {a, b, c, a, c, d});
    wood.materialIds.insert(wood.materialIds.end(), {0, 0});
  }
}

Leaf makeLeaf(const Turtle& turtle, const Module& m, const LSystemTreeParams& params,
              Random& random) {
  const float scale = m.p[0], pitch = m.p[1] * kDegToRad, roll = m.p[2] * kDegToRad;
  const glm::vec3 side = turtle.left * std::cos(roll) + turtle.up * std::sin(roll);
  // Leaves stand off the twig on petioles and short spurs, so foliage fills the crown volume.
  const glm::vec3 base =
      turtle.position - turtle.heading * m.p[3] + side * (params.leafSpread * random.uniform());
  const glm::vec3 direction =
      glm::normalize(turtle.heading * std::cos(pitch) + side * std::sin(pitch));
  // The blade's width axis: horizontal where possible, twisted randomly by up to ±35°.
  glm::vec3 across = glm::cross(direction, glm::vec3(0.0f, 1.0f, 0.0f));
  if (glm::length(across) < 0.05f) across = side;
  across = glm::normalize(across);
  const float twist = random.uniform(-35.0f, 35.0f) * kDegToRad;
  const glm::vec3 faceUp = glm::normalize(glm::cross(across, direction));
  across = glm::normalize(across * std::cos(twist) + faceUp * std::sin(twist));
  Leaf leaf;
  leaf.axisV = direction;
  leaf.axisU = across;
  leaf.normal = glm::normalize(glm::cross(leaf.axisU, leaf.axisV));
  // Most leaves turn their front side to the sky; flipping axisU mirrors the symmetric texture.
  if (leaf.normal.y < 0.0f && random.uniform() < 0.85f) {
    leaf.axisU = -leaf.axisU;
    leaf.normal = -leaf.normal;
  }
  leaf.halfExtents = {0.5f * params.leafWidth * scale, 0.5f * params.leafLength * scale};
  leaf.center = base + direction * leaf.halfExtents.y;
  leaf.uvMin = {0.0f, 0.0f};
  leaf.uvMax = {1.0f, 1.0f};
  leaf.texture = random.below(static_cast<uint32_t>(params.leafTextureVariants));
  leaf.branch = turtle.node;
  return leaf;
}

void validateParams(const LSystemTreeParams& params) {
  const auto require = [&](bool ok, const char* key, auto value) {
    if (!ok)
      throwInputError("tree preset '{}': parameter '{}' out of range ({})", params.preset, key,
                      value);
  };
  require(params.iterations >= 1 && params.iterations <= 14, "iterations", params.iterations);
  require(params.leaves >= 1 && params.leaves <= 2'000'000, "leaves", params.leaves);
  require(params.stems >= 1 && params.stems <= 32, "stems", params.stems);
  require(params.leafTextureVariants >= 1 && params.leafTextureVariants <= 8,
          "leaf_texture_variants", params.leafTextureVariants);
  require(params.leafTextureSize >= 16 && params.leafTextureSize <= 2048, "leaf_texture_size",
          params.leafTextureSize);
  require(params.leafLength > 0 && params.leafWidth > 0, "leaf_length", params.leafLength);
}

}  // namespace

LSystemTreeParams treePreset(const std::string& name) {
  LSystemTreeParams params;
  params.preset = name;
  if (name == "broadleaf") {
    // Defaults: a single-trunk deciduous tree of about 11 m like the papers' oak and chestnut.
    params.iterations = 8;
    params.maxOrder = 4;
    params.boleLength = 2.2f;
    params.trunkLength = 1.1f;
    params.mainLengthRatio = 0.86f;
    params.lateralLengthRatio = 0.92f;
    params.branchAngle = 52.0f;
    params.tropism = 0.02f;
    params.leafOrder = 2;
    params.leaves = 20000;
  } else if (name == "shrub") {
    params.iterations = 5;
    params.maxOrder = 4;
    params.stems = 5;
    params.stemSpread = 28.0f;
    params.boleLength = 0.1f;
    params.trunkLength = 0.45f;
    params.trunkRadius = 0.04f;
    params.branchAngle = 38.0f;
    params.tropism = 0.03f;
    params.leafOrder = 1;
    params.leaves = 2500;
    params.leafLength = 0.13f;
    params.leafWidth = 0.075f;
    params.leafSpread = 0.12f;
  } else if (name == "sparse") {
    params.iterations = 7;
    params.maxOrder = 3;
    params.boleLength = 2.0f;
    params.trunkLength = 1.3f;
    params.trunkRadius = 0.15f;
    params.branchAngle = 50.0f;
    params.leaves = 1000;
    params.leafLength = 0.2f;
    params.leafWidth = 0.11f;
  } else {
    throwInputError("unknown tree preset '{}' (known: broadleaf, shrub, sparse)", name);
  }
  return params;
}

std::vector<std::string> treePresetNames() {
  return {"broadleaf", "shrub", "sparse"};
}

std::vector<Module> deriveTreeString(const LSystemTreeParams& params, uint64_t seed) {
  validateParams(params);
  Random random(seed, 0x1f2e3d4c5b6a7988ULL);
  std::vector<Module> modules;
  const float firstRadius = params.trunkRadius * params.mainRadiusRatio;
  if (params.stems == 1) {
    modules.push_back(Module::make('F', params.boleLength, params.trunkRadius, 0.0f));
    modules.push_back(Module::make('A', params.trunkLength, firstRadius, 0.0f));
  } else {
    for (int s = 0; s < params.stems; ++s) {
      modules.push_back(Module::make('['));
      modules.push_back(
          Module::make('/', 360.0f * float(s) / float(params.stems) + random.uniform(-15, 15)));
      modules.push_back(Module::make('&', params.stemSpread + random.uniform(-8, 8)));
      modules.push_back(Module::make('F', params.boleLength, params.trunkRadius, 0.0f));
      modules.push_back(Module::make('A', params.trunkLength, firstRadius, 0.0f));
      modules.push_back(Module::make(']'));
    }
  }
  for (int step = 0; step < params.iterations; ++step) {
    std::vector<Module> next;
    next.reserve(modules.size() * 2);
    for (const Module& m : modules) {
      if (m.symbol == 'A') {
        rewriteApex(m, params, random, next);
      } else {
        next.push_back(m);
      }
    }
    modules.swap(next);
  }
  // Remaining apices become the last, leaf-bearing twig segments.
  for (Module& m : modules) {
    if (m.symbol == 'A') {
      m.symbol = 'F';
      m.p[2] = std::max(m.p[2], float(params.leafOrder));
    }
  }
  return distributeLeaves(modules, params, random);
}

Tree interpretTreeString(const std::vector<Module>& modules, const LSystemTreeParams& params,
                         uint64_t seed) {
  Random random(seed, 0x3c6ef372fe94f82bULL);
  Tree tree;
  tree.name = params.preset;
  tree.wood.solid = true;  // addCylinder winds every tube's quads counter-clockwise from outside
  tree.woodMaterials.push_back({"bark", glm::vec4(0.36f, 0.26f, 0.18f, 1.0f), -1});
  tree.branches.push_back(BranchNode{});  // the root box: the trunk
  std::vector<Turtle> stack;
  Turtle turtle;
  for (const Module& m : modules) {
    switch (m.symbol) {
      case 'F': {
        const int sides = sidesForRadius(m.p[1], params.trunkRadius);
        addCylinder(tree.wood, turtle, m.p[0], m.p[1], m.p[1] * params.mainRadiusRatio, sides,
                    tree.branches[turtle.node].bounds);
        turtle.position += turtle.heading * m.p[0];
        turtle.applyTropism(params.tropism);
        break;
      }
      case '+':
        turtle.turn(m.p[0]);
        break;
      case '&':
        turtle.pitch(m.p[0]);
        break;
      case '/':
        turtle.roll(m.p[0]);
        break;
      case '[': {  // PUSH: save the turtle, open a new box one level deeper
        stack.push_back(turtle);
        BranchNode node;
        node.parent = turtle.node;
        node.level = tree.branches[turtle.node].level + 1;
        turtle.node = static_cast<int32_t>(tree.branches.size());
        tree.branches[node.parent].children.push_back(turtle.node);
        tree.branches.push_back(std::move(node));
        break;
      }
      case ']': {  // POP: close the last box, restore the turtle
        if (stack.empty())
          throwInputError("preset '{}': unbalanced POP in L-system string", params.preset);
        turtle = stack.back();
        stack.pop_back();
        break;
      }
      case 'L':
        tree.leaves.push_back(makeLeaf(turtle, m, params, random));
        break;
      default:
        throwInputError("preset '{}': unknown module '{}'", params.preset, m.symbol);
    }
  }
  if (!stack.empty())
    throwInputError("preset '{}': unbalanced PUSH in L-system string", params.preset);
  return tree;
}

Tree generateTree(const LSystemTreeParams& params, uint64_t seed) {
  Tree tree = interpretTreeString(deriveTreeString(params, seed), params, seed);
  for (int v = 0; v < params.leafTextureVariants; ++v) {
    tree.leafTextures.push_back(drawLeafTexture(params.leafTextureSize, static_cast<uint32_t>(v)));
  }
  indexLeavesByBranch(tree);
  finalizeTree(tree, "preset " + params.preset);
  return tree;
}

}  // namespace canopy
