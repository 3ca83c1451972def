#pragma once

#include <vector>

#include "common/config.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// Parameters every billboard-cloud method shares: the clustering and the geometric LoD.
struct CloudParams {
  ClusteringParams clustering;
  // Three clouds of K, K/3, K/10 billboards, switched per instance by the tree's projected size
  // in output pixels (the bounding radius as FrameContext::projectedPixels measures it).
  bool lod = true;
  float lodNearPixels = 120.0f;  // the K cloud while the radius spans at least this many pixels
  float lodFarPixels = 35.0f;    // the K/10 cloud below this; K/3 in between

  template <class Visitor>
  void visit(Visitor& v) {
    v("clusters", clustering.clusters, 1, 100000);
    v("orientation_weight", clustering.orientationWeight, 0.0f, 1000.0f);
    v("compactness_weight", clustering.compactnessWeight, 0.0f, 1000.0f);
    v("cluster_iterations", clustering.iterations, 1, 1000);
    v("lod", lod);
    v("lod_near_px", lodNearPixels, 0.01f, 100000.0f);
    v("lod_far_px", lodFarPixels, 0.01f, 100000.0f);
  }

  std::vector<int> divisors() const {
    return lod ? std::vector<int>{1, 3, 10} : std::vector<int>{1};
  }
  // Projected radii (output pixels) below which the next coarser cloud is drawn, decreasing.
  std::vector<float> thresholds() const {
    return lod ? std::vector<float>{lodNearPixels, lodFarPixels} : std::vector<float>{};
  }
  void validate(const std::string& method) const {
    if (lod && lodFarPixels >= lodNearPixels)
      throwInputError("{}: parameter 'lod_far_px' ({}) must be below 'lod_near_px' ({})", method,
                      lodFarPixels, lodNearPixels);
  }
};

// A summary of a cloud family for bake reports.
nlohmann::json describeClouds(const std::vector<BillboardCloud>& clouds);

}  // namespace canopy
