#pragma once

#include <vector>

#include "common/config.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// Parameters every billboard-cloud method shares: the clustering and the geometric LoD.
struct CloudParams {
  ClusteringParams clustering;
  bool lod = true;       // three clouds of K, K/3, K/10 billboards, switched by distance
  float lodNear = 6.0f;  // below this distance (bounding radii) the K cloud is drawn
  float lodFar = 20.0f;  // beyond this distance the K/10 cloud; K/3 in between

  template <class Visitor>
  void visit(Visitor& v) {
    v("clusters", clustering.clusters, 1, 100000);
    v("orientation_weight", clustering.orientationWeight, 0.0f, 1000.0f);
    v("compactness_weight", clustering.compactnessWeight, 0.0f, 1000.0f);
    v("cluster_iterations", clustering.iterations, 1, 1000);
    v("lod", lod);
    v("lod_near", lodNear, 1.0f, 10000.0f);
    v("lod_far", lodFar, 1.0f, 10000.0f);
  }

  std::vector<int> divisors() const {
    return lod ? std::vector<int>{1, 3, 10} : std::vector<int>{1};
  }
  std::vector<float> thresholds() const {
    return lod ? std::vector<float>{lodNear, lodFar} : std::vector<float>{};
  }
  void validate(const std::string& method) const {
    if (lod && lodFar <= lodNear)
      throwInputError("{}: parameter 'lod_far' ({}) must exceed 'lod_near' ({})", method, lodFar,
                      lodNear);
  }
};

// A summary of a cloud family for bake reports.
nlohmann::json describeClouds(const std::vector<BillboardCloud>& clouds);

}  // namespace canopy
