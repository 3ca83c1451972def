#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/config.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// Parameters every billboard-cloud method shares: the clustering and the geometric LoD (three
// clouds of K, K/3, K/10 billboards, switched per instance by the tree's projected size in
// output pixels, the bounding radius as FrameContext::projectedPixels measures it). Each field is
// documented where visit() names it.
struct CloudParams {
  ClusteringParams clustering;
  float coarseCompactnessWeight = 1.0f;
  bool lod = true;
  float lodNearPixels = 120.0f;
  float lodFarPixels = 35.0f;

  template <class Visitor>
  void visit(Visitor& v) {
    v("clusters", clustering.clusters, 1, 100000,
      "K, clusters (planes) of the finest cloud; K/3 and K/10 for the coarser ones");
    v("orientation_weight", clustering.orientationWeight, 0.0f, 1000.0f,
      "clustering: weight of the leaf-orientation term");
    v("compactness_weight", clustering.compactnessWeight, 0.0f, 1000.0f,
      "clustering: weight of the locality term");
    v("cluster_iterations", clustering.iterations, 1, 1000,
      "clustering: assignment/refit rounds at most (stops when stable)");
    v("split_gap", clustering.splitGap, 0.0f, 1000.0f,
      "clustering: a plane's leaves farther apart than this many mean leaf lengths get separate "
      "billboards (0: one billboard per cluster)");
    v("coarse_compactness_weight", coarseCompactnessWeight, 0.0f, 1000.0f,
      "clustering of the K/3 and K/10 clouds (far trees, never split): weight of the locality "
      "term");
    v("lod", lod, "three clouds of K, K/3, K/10 billboards switched by projected size (§6)");
    v("lod_near_px", lodNearPixels, 0.01f, 100000.0f,
      "the K cloud while the tree's bounding radius spans at least this many output pixels");
    v("lod_far_px", lodFarPixels, 0.01f, 100000.0f,
      "the K/10 cloud below this projected radius (output pixels); K/3 in between");
  }

  // The clustering of each cloud, finest first: the K cloud as configured; the K/3 and K/10
  // clouds, drawn for far trees where fragments are what costs, spatially compact and unsplit.
  std::vector<ClusteringParams> levels() const {
    std::vector<ClusteringParams> out{clustering};
    if (!lod) return out;
    for (const int divisor : {3, 10}) {
      ClusteringParams coarse = clustering;
      coarse.clusters =
          std::max(1, static_cast<int>(std::lround(double(clustering.clusters) / divisor)));
      coarse.compactnessWeight = coarseCompactnessWeight;
      coarse.splitGap = 0.0f;
      out.push_back(coarse);
    }
    return out;
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
