#include "methods/common/wood_capture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include <glm/geometric.hpp>

#include "common/error.h"

namespace canopy {

namespace {

// The largest distance of `corners` from the billboard's plane when every corner projects into
// its rectangle; nothing when one does not.
template <class Corners>
std::optional<float> planeDistanceInside(const Billboard& billboard, const Corners& corners) {
  float distance = 0.0f;
  for (const glm::vec3& p : corners) {
    const glm::vec2 q = billboard.toPlane(p);
    if (std::abs(q.x) > billboard.halfExtents.x || std::abs(q.y) > billboard.halfExtents.y)
      return std::nullopt;
    distance = std::max(distance, std::abs(glm::dot(p - billboard.center, billboard.normal)));
  }
  return distance;
}

}  // namespace

std::vector<uint32_t> woodParts(const WoodMesh& wood) {
  const std::vector<uint32_t> ofVertex = wood.vertexParts();
  // Renumbered in the order of the parts' first triangles, as the header promises.
  std::vector<uint32_t> part(wood.triangleCount()), number(ofVertex.size(), UINT32_MAX);
  uint32_t parts = 0;
  for (size_t t = 0; t < part.size(); ++t) {
    uint32_t& n = number[ofVertex[wood.indices[t * 3]]];
    if (n == UINT32_MAX) n = parts++;
    part[t] = n;
  }
  return part;
}

std::vector<std::vector<uint32_t>> assignWoodPartsToBillboards(
    const WoodMesh& wood, const std::vector<uint32_t>& parts,
    const std::vector<Billboard>& billboards, float maxDistance) {
  const uint32_t partCount =
      parts.empty() ? 0u : *std::max_element(parts.begin(), parts.end()) + 1u;
  std::vector<std::vector<glm::vec3>> corners(partCount);
  for (size_t t = 0; t < parts.size(); ++t)
    for (int k = 0; k < 3; ++k)
      corners[parts[t]].push_back(wood.positions[wood.indices[t * 3 + k]]);
  // The nearest plane, whatever the part faces: on the presets' far rings it beat the plane the
  // part shows most area to (docs/METHODS.md, "the far cloud's own bound").
  std::vector<size_t> target(partCount, billboards.size());
  for (uint32_t part = 0; part < partCount; ++part) {
    float bestDistance = std::numeric_limits<float>::max();
    for (size_t b = 0; b < billboards.size(); ++b) {
      const std::optional<float> distance = planeDistanceInside(billboards[b], corners[part]);
      if (distance && *distance <= maxDistance && *distance < bestDistance) {
        target[part] = b;
        bestDistance = *distance;
      }
    }
  }
  std::vector<std::vector<uint32_t>> assigned(billboards.size());
  for (size_t t = 0; t < parts.size(); ++t)
    if (target[parts[t]] < billboards.size())
      assigned[target[parts[t]]].push_back(static_cast<uint32_t>(t));
  return assigned;
}

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
    const std::array<glm::vec3, 3> corners = {a, wood.positions[wood.indices[triangle * 3 + 1]],
                                              wood.positions[wood.indices[triangle * 3 + 2]]};
    for (size_t b = 0; b < billboards.size(); ++b) {
      const Billboard& billboard = billboards[b];
      const std::optional<float> within = planeDistanceInside(billboard, corners);
      if (!within || *within > maxDistance) continue;
      const float distance = *within;
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
                                 float capturePixels, float farCapturePixels, bool wholeParts) {
  WoodInImages result;
  size_t total = 0;
  for (const BillboardCloud& cloud : clouds) total += cloud.billboards.size();
  result.perBillboard.resize(total);
  result.report = {{"triangles", 0}};
  if ((capturePixels <= 0.0f && farCapturePixels <= 0.0f) || clouds.size() <= firstImageCloud)
    return result;
  const float radius = 0.5f * glm::length(tree.bounds.extent());
  const size_t triangles = tree.wood.triangleCount();
  const size_t imageClouds = clouds.size() - firstImageCloud;
  const std::vector<uint32_t> parts = wholeParts ? woodParts(tree.wood) : std::vector<uint32_t>{};
  // Each image cloud's triangles within `pixels` of its billboards, and where they go.
  const auto within = [&](size_t c, float pixels, std::vector<bool>& held) {
    const float maxDistance = pixels * radius / largestPixels.at(c - firstImageCloud);
    auto assigned =
        wholeParts
            ? assignWoodPartsToBillboards(tree.wood, parts, clouds[c].billboards, maxDistance)
            : assignWoodToBillboards(tree.wood, clouds[c].billboards, maxDistance);
    held.assign(triangles, false);
    for (const auto& list : assigned)
      for (uint32_t t : list) held[t] = true;
    return std::make_pair(maxDistance, std::move(assigned));
  };
  std::vector<std::vector<std::vector<uint32_t>>> assigned(imageClouds);
  nlohmann::json bounds = nlohmann::json::array();
  std::vector<bool> shared(triangles, capturePixels > 0.0f);  // what every image cloud holds
  for (size_t i = 0; i < imageClouds; ++i) {
    if (capturePixels <= 0.0f) break;
    std::vector<bool> inCloud;
    auto [distance, lists] = within(firstImageCloud + i, capturePixels, inCloud);
    bounds.push_back(distance);
    assigned[i] = std::move(lists);
    for (size_t t = 0; t < triangles; ++t) shared[t] = shared[t] && inCloud[t];
  }
  nlohmann::json farReport;
  const bool ownFar = farCapturePixels > 0.0f;
  std::vector<bool> farHeld;  // with ownFar: what the last image cloud holds, on its own
  if (ownFar) {
    auto [distance, lists] = within(clouds.size() - 1, farCapturePixels, farHeld);
    assigned.back() = std::move(lists);
    farReport = {{"triangles", size_t(std::count(farHeld.begin(), farHeld.end(), true))},
                 {"max_plane_distance", distance},
                 {"below_px", largestPixels.back()}};
  }
  const auto heldBy = [&](size_t i) -> const std::vector<bool>& {
    return ownFar && i + 1 == imageClouds ? farHeld : shared;
  };
  size_t first = 0;
  for (size_t c = 0; c < firstImageCloud; ++c) first += clouds[c].billboards.size();
  for (size_t i = 0; i < imageClouds; ++i) {
    for (const auto& list : assigned[i]) {
      for (uint32_t t : list)
        if (heldBy(i)[t]) result.perBillboard[first].push_back(t);
      ++first;
    }
  }
  const auto count = size_t(std::count(shared.begin(), shared.end(), true));
  // (A chain even when nothing was captured, so that the levels do not depend on the count.)
  if (capturePixels > 0.0f && !(ownFar && imageClouds == 1))
    result.captured.push_back({shared, largestPixels.front()});
  if (ownFar) result.captured.push_back({farHeld, largestPixels.back()});
  result.report = {
      {"triangles", count}, {"max_plane_distance", bounds}, {"below_px", largestPixels.front()}};
  if (ownFar) result.report["far"] = farReport;
  return result;
}

void resolveWoodCapture(const char* method, bool lod, bool wood, float& capturePixels,
                        float& farCapturePixels) {
  if (!lod || !wood) {
    capturePixels = 0.0f;
    farCapturePixels = 0.0f;
  }
  if (farCapturePixels > 0.0f && farCapturePixels < capturePixels)
    throwInputError(
        "{}: parameter 'wood_capture_far_px' ({}) must be at least 'wood_capture_px' ({}), or be 0",
        method, farCapturePixels, capturePixels);
}

}  // namespace canopy
