#include "methods/common/billboard_cloud.h"

#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include <glm/geometric.hpp>

#include "common/error.h"
#include "common/random.h"

namespace canopy {

glm::vec3 Billboard::corner(int i) const {
  static constexpr float kSignU[4] = {-1, 1, 1, -1};
  static constexpr float kSignV[4] = {-1, -1, 1, 1};
  return center + axisU * (kSignU[i] * halfExtents.x) + axisV * (kSignV[i] * halfExtents.y);
}

glm::vec2 Billboard::toPlane(const glm::vec3& p) const {
  const glm::vec3 d = p - center;
  return {glm::dot(d, axisU), glm::dot(d, axisV)};
}

namespace {

double cross2(const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Andrew's monotone chain; counter-clockwise, no collinear points.
std::vector<glm::dvec2> convexHull(std::vector<glm::dvec2> points) {
  std::sort(points.begin(), points.end(), [](const glm::dvec2& a, const glm::dvec2& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  std::vector<glm::dvec2> hull(2 * points.size());
  size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross2(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

struct Plane {
  glm::vec3 origin{0.0f};
  glm::vec3 normal{0, 0, 1};
};

// The plane that minimises a cluster's share of the clustering cost: through the centroid of
// the leaf corners, with the normal N minimising Nᵀ(¼·C − w·S)N, where C is the corners'
// scatter about their centroid (¼ of it: the fit term averages a leaf's four corners) and
// S = Σ n nᵀ the leaves' normal scatter weighted by the orientation scale w: the eigenvector of
// the smallest eigenvalue. With w = 0 it is the least-squares plane of the corners; the larger w,
// the more the normal follows the leaves' own orientations. Assignment and refit minimise the
// same cost, so the iteration descends.
Plane fitPlane(const std::vector<glm::vec3>& points, const std::vector<glm::vec3>& leafNormals,
               float orientationScale, const glm::vec3& preferredSide) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const glm::vec3& p : points) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= double(points.size());
  Eigen::Matrix3d cost = Eigen::Matrix3d::Zero();
  for (const glm::vec3& p : points) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    cost += 0.25 * d * d.transpose();
  }
  for (const glm::vec3& n : leafNormals) {
    const Eigen::Vector3d e(n.x, n.y, n.z);
    cost -= double(orientationScale) * e * e.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cost);
  const Eigen::Vector3d n = solver.eigenvectors().col(0);  // eigenvalues ascend
  Plane plane;
  plane.origin = glm::vec3(mean.x(), mean.y(), mean.z());
  plane.normal = glm::normalize(glm::vec3(n.x(), n.y(), n.z()));
  if (glm::dot(plane.normal, preferredSide) < 0.0f) plane.normal = -plane.normal;
  return plane;
}

struct LeafFeatures {
  glm::vec3 center;
  glm::vec3 normal;
  glm::vec3 corners[4];
};

glm::vec3 anyPerpendicular(const glm::vec3& n) {
  const glm::vec3 helper = std::abs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  return glm::normalize(glm::cross(helper, n));
}

}  // namespace

Rectangle2D minimumAreaRectangle(const std::vector<glm::vec2>& points) {
  std::vector<glm::dvec2> input;
  input.reserve(points.size());
  for (const glm::vec2& p : points) input.emplace_back(p);
  const std::vector<glm::dvec2> hull = convexHull(input);
  Rectangle2D best;
  if (hull.empty()) return best;
  double bestArea = std::numeric_limits<double>::max();
  const size_t n = hull.size();
  for (size_t i = 0; i < std::max<size_t>(n, 1); ++i) {
    glm::dvec2 edge = n >= 2 ? hull[(i + 1) % n] - hull[i] : glm::dvec2(1, 0);
    if (glm::length(edge) <= 0) continue;
    edge = glm::normalize(edge);
    const glm::dvec2 normal(-edge.y, edge.x);
    double minU = std::numeric_limits<double>::max(), maxU = -minU, minV = minU, maxV = -minU;
    for (const glm::dvec2& p : hull) {
      const double u = glm::dot(p, edge), v = glm::dot(p, normal);
      minU = std::min(minU, u), maxU = std::max(maxU, u);
      minV = std::min(minV, v), maxV = std::max(maxV, v);
    }
    const double area = (maxU - minU) * (maxV - minV);
    if (area < bestArea - 1e-12) {
      bestArea = area;
      const glm::dvec2 center = edge * (0.5 * (minU + maxU)) + normal * (0.5 * (minV + maxV));
      best.center = glm::vec2(center);
      best.axis = glm::vec2(edge);
      best.halfExtents = glm::vec2(0.5 * (maxU - minU), 0.5 * (maxV - minV));
    }
  }
  return best;
}

namespace {

// Leaves of one plane grouped so that two groups' leaves lie more than `gap` apart on the plane
// (their projected bounding boxes, each grown by gap / 2, do not overlap): union-find over a
// sweep along the first plane axis. Groups in order of their first leaf, leaves in input order.
std::vector<std::vector<uint32_t>> splitIntoGroups(const Tree& tree, const glm::vec3& normal,
                                                   const std::vector<uint32_t>& leaves, float gap) {
  const glm::vec3 e1 = anyPerpendicular(normal), e2 = glm::cross(normal, e1);
  const size_t n = leaves.size();
  std::vector<glm::vec2> lo(n, glm::vec2(std::numeric_limits<float>::max())),
      hi(n, glm::vec2(std::numeric_limits<float>::lowest()));
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 4; ++c) {
      const glm::vec3 p = tree.leaves[leaves[i]].corner(c);
      const glm::vec2 q(glm::dot(p, e1), glm::dot(p, e2));
      lo[i] = glm::min(lo[i], q - 0.5f * gap);
      hi[i] = glm::max(hi[i], q + 0.5f * gap);
    }
  }
  std::vector<size_t> parent(n), order(n);
  std::iota(parent.begin(), parent.end(), size_t(0));
  std::iota(order.begin(), order.end(), size_t(0));
  const auto root = [&](size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return lo[a].x < lo[b].x || (lo[a].x == lo[b].x && a < b); });
  for (size_t a = 0; a < n; ++a) {
    const size_t i = order[a];
    for (size_t b = a + 1; b < n && lo[order[b]].x <= hi[i].x; ++b) {
      const size_t j = order[b];
      if (lo[j].y > hi[i].y || lo[i].y > hi[j].y) continue;
      const size_t ri = root(i), rj = root(j);
      if (ri != rj) parent[std::max(ri, rj)] = std::min(ri, rj);
    }
  }
  std::vector<std::vector<uint32_t>> groups;
  std::vector<size_t> groupOfRoot(n, SIZE_MAX);
  for (size_t i = 0; i < n; ++i) {
    const size_t r = root(i);
    if (groupOfRoot[r] == SIZE_MAX) {
      groupOfRoot[r] = groups.size();
      groups.emplace_back();
    }
    groups[groupOfRoot[r]].push_back(leaves[i]);
  }
  return groups;
}

// The billboard of `leaves` on `plane`: the minimum-area rectangle of their projected corners.
Billboard makeBillboard(const Tree& tree, const Plane& plane, const std::vector<uint32_t>& leaves) {
  Billboard billboard;
  const glm::vec3 e1 = anyPerpendicular(plane.normal);
  const glm::vec3 e2 = glm::cross(plane.normal, e1);
  std::vector<glm::vec2> projected;
  double distanceSum = 0.0;
  for (uint32_t i : leaves) {
    const Leaf& leaf = tree.leaves[i];
    for (int c = 0; c < 4; ++c) {
      const glm::vec3 d = leaf.corner(c) - plane.origin;
      projected.emplace_back(glm::dot(d, e1), glm::dot(d, e2));
      const float distance = std::abs(glm::dot(d, plane.normal));
      distanceSum += distance;
      billboard.maxPlaneDistance = std::max(billboard.maxPlaneDistance, distance);
    }
    const float alignment = std::abs(glm::dot(plane.normal, leaf.normal));
    billboard.projectedLeafArea += leaf.area() * alignment;
    billboard.alignmentSum += alignment;
  }
  const Rectangle2D rectangle = minimumAreaRectangle(projected);
  billboard.normal = plane.normal;
  billboard.axisU = glm::normalize(e1 * rectangle.axis.x + e2 * rectangle.axis.y);
  billboard.axisV = glm::normalize(glm::cross(plane.normal, billboard.axisU));
  billboard.center = plane.origin + e1 * rectangle.center.x + e2 * rectangle.center.y;
  billboard.halfExtents = rectangle.halfExtents;
  billboard.leaves = leaves;
  billboard.meanPlaneDistance = float(distanceSum / double(4 * leaves.size()));
  return billboard;
}

}  // namespace

BillboardCloud buildBillboardCloud(const Tree& tree, const ClusteringParams& params,
                                   uint64_t seed) {
  const auto start = std::chrono::steady_clock::now();
  const size_t leafCount = tree.leaves.size();
  if (params.clusters <= 0)
    throwInputError("parameter 'clusters' = {} must be at least 1", params.clusters);
  if (leafCount == 0) throwInputError("a billboard cloud needs leaves; the tree has none");
  // A plane per leaf at most: a default K sized for full trees still works on small ones, and
  // the report's `clusters` says how many planes there were.
  const int k = static_cast<int>(std::min(size_t(params.clusters), leafCount));
  std::vector<LeafFeatures> leaves(leafCount);
  double leafSize = 0.0;
  for (size_t i = 0; i < leafCount; ++i) {
    const Leaf& leaf = tree.leaves[i];
    leaves[i].center = leaf.center;
    leaves[i].normal = leaf.normal;
    for (int c = 0; c < 4; ++c) leaves[i].corners[c] = leaf.corner(c);
    leafSize += std::max(leaf.halfExtents.x, leaf.halfExtents.y) * 2.0;
  }
  const float L2 = float(std::pow(leafSize / double(leafCount), 2.0));
  const float localRadius = tree.boundingSphereRadius() / std::cbrt(float(k));
  const float orientationScale = params.orientationWeight * L2;
  const float compactnessScale = params.compactnessWeight * L2 / (localRadius * localRadius);

  // k-means++ seeding on leaf centres (deterministic in the seed).
  Random random(seed, 0x9e3779b97f4a7c15ULL);
  std::vector<Plane> planes(k);
  std::vector<glm::vec3> centroids(k);
  std::vector<float> nearest(leafCount, std::numeric_limits<float>::max());
  size_t chosen = random.below(static_cast<uint32_t>(leafCount));
  for (int c = 0; c < k; ++c) {
    planes[c] = {leaves[chosen].center, leaves[chosen].normal};
    centroids[c] = leaves[chosen].center;
    double total = 0.0;
    for (size_t i = 0; i < leafCount; ++i) {
      const glm::vec3 d = leaves[i].center - centroids[c];
      nearest[i] = std::min(nearest[i], glm::dot(d, d));
      total += nearest[i];
    }
    double target = random.uniform() * total;
    chosen = leafCount - 1;
    for (size_t i = 0; i < leafCount; ++i) {
      target -= nearest[i];
      if (target < 0) {
        chosen = i;
        break;
      }
    }
  }

  std::vector<int> assignment(leafCount, -1);
  std::vector<float> cost(leafCount, 0.0f);
  BillboardCloud cloud;
  cloud.clusters = k;
  for (int iteration = 0; iteration < params.iterations; ++iteration) {
    // Assign every leaf to its cheapest cluster (independent per leaf: parallel, deterministic).
    std::vector<int> next(leafCount);
    tbb::parallel_for(size_t(0), leafCount, [&](size_t i) {
      const LeafFeatures& leaf = leaves[i];
      float best = std::numeric_limits<float>::max();
      int bestCluster = 0;
      for (int c = 0; c < k; ++c) {
        const Plane& plane = planes[c];
        float fit = 0.0f;
        for (const glm::vec3& corner : leaf.corners) {
          const float d = glm::dot(plane.normal, corner - plane.origin);
          fit += d * d;
        }
        const float alignment = glm::dot(plane.normal, leaf.normal);
        const glm::vec3 offset = leaf.center - centroids[c];
        const float total = 0.25f * fit + orientationScale * (1.0f - alignment * alignment) +
                            compactnessScale * glm::dot(offset, offset);
        if (total < best) {
          best = total;
          bestCluster = c;
        }
      }
      next[i] = bestCluster;
      cost[i] = best;
    });
    const bool stable = next == assignment;
    assignment.swap(next);
    cloud.iterationsRun = iteration + 1;
    // Refit: group leaves per cluster (sequential, in leaf order), reseed empty clusters at the
    // worst-fitting leaf, fit planes in parallel.
    std::vector<std::vector<uint32_t>> members(k);
    for (size_t i = 0; i < leafCount; ++i)
      members[assignment[i]].push_back(static_cast<uint32_t>(i));
    for (int c = 0; c < k; ++c) {
      if (!members[c].empty()) continue;
      size_t worst = 0;
      for (size_t i = 1; i < leafCount; ++i) {
        if (cost[i] > cost[worst] && members[assignment[i]].size() > 1) worst = i;
      }
      auto& donor = members[assignment[worst]];
      donor.erase(std::find(donor.begin(), donor.end(), static_cast<uint32_t>(worst)));
      members[c].push_back(static_cast<uint32_t>(worst));
      assignment[worst] = c;
      cost[worst] = 0.0f;
    }
    tbb::parallel_for(0, k, [&](int c) {
      std::vector<glm::vec3> points, normals;
      glm::vec3 normalSum(0.0f), centroid(0.0f);
      for (uint32_t i : members[c]) {
        for (const glm::vec3& corner : leaves[i].corners) points.push_back(corner);
        normals.push_back(leaves[i].normal);
        normalSum += leaves[i].normal;
        centroid += leaves[i].center;
      }
      planes[c] = fitPlane(points, normals, orientationScale, normalSum);
      centroids[c] = centroid / float(members[c].size());
    });
    if (stable) break;
  }

  // Billboards: each cluster's plane, cut into groups of leaves that lie apart on it, each
  // group bounded by the minimum-area rectangle of its leaves' projected corners.
  std::vector<std::vector<uint32_t>> members(k);
  for (size_t i = 0; i < leafCount; ++i) members[assignment[i]].push_back(static_cast<uint32_t>(i));
  const float gap = params.splitGap * float(leafSize / double(leafCount));
  std::vector<std::vector<std::vector<uint32_t>>> groups(k);
  tbb::parallel_for(0, k, [&](int c) {
    groups[c] = params.splitGap > 0.0f ? splitIntoGroups(tree, planes[c].normal, members[c], gap)
                                       : std::vector<std::vector<uint32_t>>{members[c]};
  });
  std::vector<std::pair<int, const std::vector<uint32_t>*>> pieces;
  for (int c = 0; c < k; ++c)
    for (const auto& group : groups[c]) pieces.emplace_back(c, &group);
  cloud.billboards.resize(pieces.size());
  tbb::parallel_for(size_t(0), pieces.size(), [&](size_t b) {
    cloud.billboards[b] = makeBillboard(tree, planes[pieces[b].first], *pieces[b].second);
  });
  double distanceSum = 0.0, alignmentSum = 0.0;
  for (const Billboard& billboard : cloud.billboards) {
    distanceSum += double(billboard.meanPlaneDistance) * 4.0 * double(billboard.leaves.size());
    cloud.maxPlaneDistance = std::max(cloud.maxPlaneDistance, billboard.maxPlaneDistance);
    cloud.quadArea += billboard.area();
    cloud.projectedLeafArea += billboard.projectedLeafArea;
    alignmentSum += billboard.alignmentSum;
  }
  cloud.meanPlaneDistance = float(distanceSum / double(4 * leafCount));
  cloud.meanAlignment = float(alignmentSum / double(leafCount));
  cloud.meanLeafLength = float(leafSize / double(leafCount));
  cloud.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return cloud;
}

std::vector<BillboardCloud> buildBillboardCloudFamily(const Tree& tree,
                                                      const std::vector<ClusteringParams>& levels,
                                                      uint64_t seed) {
  std::vector<BillboardCloud> family;
  // Each cloud's own seed: as when the family was named by the divisors 1, 3, 10.
  static constexpr uint64_t kSeedOffsets[] = {1, 3, 10};
  for (size_t level = 0; level < levels.size(); ++level)
    family.push_back(buildBillboardCloud(tree, levels[level],
                                         seed + (level < 3 ? kSeedOffsets[level] : level * 10)));
  return family;
}

}  // namespace canopy
