#include "methods/common/view_orders.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "common/random.h"

namespace canopy {
namespace {

TEST(ViewOrders, EveryRangeIsSortedFrontToBackForEveryDirection) {
  Random rng(7);
  std::vector<glm::vec3> centers(300);
  for (glm::vec3& c : centers)
    c = {rng.uniform(-1.0f, 1.0f), rng.uniform(0.0f, 2.0f), rng.uniform(-1.0f, 1.0f)};
  const std::vector<ViewOrders::Range> ranges = {{0, 200}, {200, 70}};  // the rest unsorted
  const ViewOrders orders = buildViewOrders(centers, ranges, 8);
  ASSERT_EQ(orders.directions.size(), 8u);
  ASSERT_EQ(orders.perDirection, 270u);
  ASSERT_EQ(orders.order.size(), 8u * 270u);
  for (int d = 0; d < 8; ++d) {
    const glm::vec3 towards = orders.directions[d];
    EXPECT_NEAR(glm::length(towards), 1.0f, 1e-5f);
    for (size_t r = 0; r < ranges.size(); ++r) {
      const uint32_t* slots = &orders.order[orders.firstSlot(d, r)];
      std::vector<uint32_t> seen(slots, slots + ranges[r].count);
      for (size_t i = 1; i < seen.size(); ++i) {
        EXPECT_GE(glm::dot(centers[seen[i - 1]], towards), glm::dot(centers[seen[i]], towards))
            << "direction " << d << " range " << r << " slot " << i;
      }
      std::sort(seen.begin(), seen.end());
      for (uint32_t i = 0; i < ranges[r].count; ++i)
        ASSERT_EQ(seen[i], ranges[r].first + i) << "a permutation of the range";
    }
  }
  EXPECT_THROW(buildViewOrders(centers, {{10, 20}}, 8), std::logic_error) << "not from 0";
  EXPECT_TRUE(buildViewOrders(centers, ranges, 0).empty());
}

TEST(ViewOrders, NearestDirectionIsTheClosestAndEightCoverTheSphere) {
  const ViewOrders orders = buildViewOrders({}, {}, 8);
  Random rng(3);
  float worst = 1.0f;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 v = glm::normalize(
        glm::vec3(rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f), rng.uniform(-1.0f, 1.0f)));
    const int nearest = orders.nearest(3.0f * v);
    for (const glm::vec3& d : orders.directions)
      ASSERT_GE(glm::dot(orders.directions[nearest], v), glm::dot(d, v) - 1e-6f);
    worst = std::min(worst, glm::dot(orders.directions[nearest], v));
  }
  // Eight evenly spread directions leave no view more than 60° from one of them.
  EXPECT_GT(worst, 0.5f);
}

}  // namespace
}  // namespace canopy
