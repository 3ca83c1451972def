#include "methods/common/wood_capture.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace canopy {

std::vector<std::vector<uint32_t>> assignWoodToBillboards(const WoodMesh& wood,
                                                          const std::vector<Billboard>& billboards,
                                                          float maxDistance) {
  std::vector<std::vector<uint32_t>> assigned(billboards.size());
  for (uint32_t triangle = 0; triangle < wood.triangleCount(); ++triangle) {
    size_t best = billboards.size();
    float bestAlignment = -1.0f, bestDistance = std::numeric_limits<float>::max();
    const glm::vec3 a = wood.positions[wood.indices[triangle * 3]];
    const glm::vec3 cross = glm::cross(wood.positions[wood.indices[triangle * 3 + 1]] - a,
                                       wood.positions[wood.indices[triangle * 3 + 2]] - a);
    const float length = glm::length(cross);
    const glm::vec3 normal = length > 0.0f ? cross / length : glm::vec3(0.0f);
    for (size_t b = 0; b < billboards.size(); ++b) {
      const Billboard& billboard = billboards[b];
      float distance = 0.0f;
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) {
        const glm::vec3 p = wood.positions[wood.indices[triangle * 3 + k]];
        const glm::vec2 q = billboard.toPlane(p);
        inside =
            std::abs(q.x) <= billboard.halfExtents.x && std::abs(q.y) <= billboard.halfExtents.y;
        distance = std::max(distance, std::abs(glm::dot(p - billboard.center, billboard.normal)));
      }
      if (!inside || distance > maxDistance) continue;
      // Most squarely facing first: the facet keeps its projected area in that plane's image
      // from every view, as a leaf does in a plane of its orientation; then the nearest.
      const float alignment = std::abs(glm::dot(normal, billboard.normal));
      if (alignment > bestAlignment + 1e-4f ||
          (alignment > bestAlignment - 1e-4f && distance < bestDistance)) {
        best = b;
        bestAlignment = alignment;
        bestDistance = distance;
      }
    }
    if (best < billboards.size()) assigned[best].push_back(triangle);
  }
  return assigned;
}

WoodInImages captureWoodInImages(const Tree& tree, const std::vector<BillboardCloud>& clouds,
                                 size_t firstImageCloud, const std::vector<float>& largestPixels,
                                 float capturePixels) {
  WoodInImages result;
  size_t total = 0;
  for (const BillboardCloud& cloud : clouds) total += cloud.billboards.size();
  result.perBillboard.resize(total);
  result.report = {{"triangles", 0}};
  if (capturePixels <= 0.0f || clouds.size() <= firstImageCloud) return result;
  const float radius = 0.5f * glm::length(tree.bounds.extent());
  std::vector<std::vector<std::vector<uint32_t>>> assigned;
  nlohmann::json bounds = nlohmann::json::array();
  result.captured.assign(tree.wood.triangleCount(), true);
  for (size_t c = firstImageCloud; c < clouds.size(); ++c) {
    const float maxDistance = capturePixels * radius / largestPixels.at(c - firstImageCloud);
    bounds.push_back(maxDistance);
    assigned.push_back(assignWoodToBillboards(tree.wood, clouds[c].billboards, maxDistance));
    std::vector<bool> inCloud(tree.wood.triangleCount(), false);
    for (const auto& triangles : assigned.back())
      for (uint32_t t : triangles) inCloud[t] = true;
    for (size_t t = 0; t < inCloud.size(); ++t)
      result.captured[t] = result.captured[t] && inCloud[t];
  }
  size_t first = 0;
  for (size_t c = 0; c < firstImageCloud; ++c) first += clouds[c].billboards.size();
  for (const auto& cloud : assigned) {
    for (const auto& triangles : cloud) {
      for (uint32_t t : triangles)
        if (result.captured[t]) result.perBillboard[first].push_back(t);
      ++first;
    }
  }
  const auto count = size_t(std::count(result.captured.begin(), result.captured.end(), true));
  result.report = {
      {"triangles", count}, {"max_plane_distance", bounds}, {"below_px", largestPixels.front()}};
  return result;
}

}  // namespace canopy
