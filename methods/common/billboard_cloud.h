#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "common/tree.h"

namespace canopy {

// How leaves are grouped into billboards (shared by billboard_cloud, single_leaf_indirect and
// multilayer_indirect). The cost of a leaf in a cluster, in units of the mean leaf size L:
//   mean over its corners of (n·(x − o))²                     plane fit
// + orientationWeight · L² · (1 − (n·n_leaf)²)                  orientation
// + compactnessWeight · L² · |c_leaf − centroid|² / r²           locality, r = R_tree / K^(1/3)
struct ClusteringParams {
  int clusters = 260;               // K, clusters (planes) of the finest cloud
  float orientationWeight = 0.25f;  // weight of the leaf-orientation term
  float compactnessWeight = 0.0f;   // weight of the locality term
  int iterations = 20;              // assignment/refit rounds at most (stops when stable)
  // A cluster's leaves that lie apart on its plane (gap above this many mean leaf lengths) get
  // billboards of their own, so a plane across the crown is no crown-sized, mostly empty quad;
  // 0 keeps one billboard per cluster.
  float splitGap = 2.0f;
};

// One billboard: a planar rectangle and the leaves it stands for.
struct Billboard {
  glm::vec3 center{0.0f};     // of the rectangle
  glm::vec3 normal{0, 0, 1};  // unit; points to the side most leaf fronts face
  glm::vec3 axisU{1, 0, 0};   // unit, in the plane, along the rectangle's first side
  glm::vec3 axisV{0, 1, 0};   // unit, normal × axisU
  glm::vec2 halfExtents{0.0f};
  std::vector<uint32_t> leaves;  // indices into Tree::leaves
  float meanPlaneDistance = 0;   // over the leaves' corners
  float maxPlaneDistance = 0;
  float projectedLeafArea = 0;  // Σ leaf area · |n·n_leaf|
  float alignmentSum = 0;       // Σ |n·n_leaf| over the leaves

  glm::vec3 corner(int i) const;  // CCW seen from +normal: (−,−) (+,−) (+,+) (−,+)
  glm::vec2 toPlane(const glm::vec3& p) const;  // coordinates along axisU, axisV from center
  float area() const { return 4.0f * halfExtents.x * halfExtents.y; }
};

struct BillboardCloud {
  std::vector<Billboard> billboards;  // at least one per cluster (more where clusters split)
  int clusters = 0;                   // planes: the requested K, at most one per leaf
  int iterationsRun = 0;
  double seconds = 0;
  float meanPlaneDistance = 0;  // over all leaf corners
  float maxPlaneDistance = 0;
  double quadArea = 0;           // Σ billboard areas
  double projectedLeafArea = 0;  // Σ projected leaf areas
  // Mean over leaves of |n·n_leaf|: a leaf drawn on its plane covers this share of its area
  // seen along the plane normal, so coverage falls with it.
  float meanAlignment = 0;
  float meanLeafLength = 0;  // mean of 2·max(half extents), the unit of the clustering cost
};

// Clusters the leaves into params.clusters billboards. Deterministic in `seed` whatever the
// thread count. Throws InputError naming "clusters" when K <= 0 or K > leaves.
BillboardCloud buildBillboardCloud(const Tree& tree, const ClusteringParams& params, uint64_t seed);

// The coarse-to-fine family for geometric level of detail: one cloud per entry of `levels`
// (finest first), each clustered with its own parameters.
std::vector<BillboardCloud> buildBillboardCloudFamily(const Tree& tree,
                                                      const std::vector<ClusteringParams>& levels,
                                                      uint64_t seed);

// The minimum-area rectangle enclosing 2D points (rotating calipers on the convex hull):
// centre, unit direction of the first side, half extents.
struct Rectangle2D {
  glm::vec2 center{0.0f};
  glm::vec2 axis{1.0f, 0.0f};
  glm::vec2 halfExtents{0.0f};
};
Rectangle2D minimumAreaRectangle(const std::vector<glm::vec2>& points);

}  // namespace canopy
