#include "methods/common/view_orders.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace canopy {

std::vector<glm::vec3> sphereDirections(int count) {
  std::vector<glm::vec3> directions;
  const float golden = 3.14159265358979f * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < count; ++i) {
    const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(count);
    const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
    const float angle = golden * float(i);
    directions.emplace_back(r * std::cos(angle), y, r * std::sin(angle));
  }
  return directions;
}

int ViewOrders::nearest(const glm::vec3& towardsViewer) const {
  int best = 0;
  float bestDot = -INFINITY;
  for (size_t d = 0; d < directions.size(); ++d) {
    const float dot = glm::dot(directions[d], towardsViewer);
    if (dot > bestDot) bestDot = dot, best = int(d);
  }
  return best;
}

ViewOrders buildViewOrders(std::span<const glm::vec3> centers,
                           const std::vector<ViewOrders::Range>& ranges, int directions) {
  ViewOrders orders;
  orders.ranges = ranges;
  for (const ViewOrders::Range& range : ranges) {
    if (range.first != orders.perDirection || size_t(range.first) + range.count > centers.size())
      throw std::logic_error("buildViewOrders: ranges must be contiguous from 0 within centres");
    orders.perDirection += range.count;
  }
  if (directions <= 0) return orders;
  orders.directions = sphereDirections(directions);
  orders.order.reserve(size_t(directions) * orders.perDirection);
  std::vector<float> depth(centers.size());
  for (const glm::vec3& direction : orders.directions) {
    for (const ViewOrders::Range& range : ranges) {
      std::vector<uint32_t> sorted(range.count);
      std::iota(sorted.begin(), sorted.end(), range.first);
      for (uint32_t i : sorted) depth[i] = glm::dot(centers[i], direction);
      std::stable_sort(sorted.begin(), sorted.end(),
                       [&](uint32_t a, uint32_t b) { return depth[a] > depth[b]; });
      orders.order.insert(orders.order.end(), sorted.begin(), sorted.end());
    }
  }
  return orders;
}

}  // namespace canopy
