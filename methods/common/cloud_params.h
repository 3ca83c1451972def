#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/config.h"
#include "methods/common/billboard_cloud.h"

namespace canopy {

// Parameters every billboard-cloud method shares: the clustering and the geometric LoD (three
// clouds of K, K/3, K/10 billboards unless set apart, switched per instance by the tree's
// projected size in output pixels, the bounding radius as FrameContext::projectedPixels measures
// it). Each field is documented where visit() names it.
struct CloudParams {
  ClusteringParams clustering;
  int midClusters = 0;  // resolve() replaces 0 by K/3
  int farClusters = 0;  // resolve() replaces 0 by K/10
  float coarseCompactnessWeight = 1.0f;
  bool lod = true;
  float lodNearPixels = 120.0f;
  float lodFarPixels = 35.0f;

  template <class Visitor>
  void visit(Visitor& v) {
    v("clusters", clustering.clusters, 1, 100000,
      "K, clusters (planes) of the finest cloud, drawn for near trees");
    v("clusters_mid", midClusters, 0, 100000,
      "clusters of the middle cloud (between lod_near_px and lod_far_px); 0: K/3");
    v("clusters_far", farClusters, 0, 100000,
      "clusters of the far cloud (below lod_far_px); 0: K/10");
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
      "clustering of the middle and far clouds (far trees, never split): weight of the locality "
      "term");
    v("lod", lod, "three clouds (K, clusters_mid, clusters_far) switched by projected size (§6)");
    v("lod_near_px", lodNearPixels, 0.01f, 100000.0f,
      "the K cloud while the tree's bounding radius spans at least this many output pixels");
    v("lod_far_px", lodFarPixels, 0.01f, 100000.0f,
      "the far cloud below this projected radius (output pixels); the middle one in between");
  }

  // The clustering of each cloud, finest first: the K cloud as configured; the middle and far
  // clouds, drawn for far trees where fragments are what costs, spatially compact and unsplit.
  // Call resolve() first.
  std::vector<ClusteringParams> levels() const {
    std::vector<ClusteringParams> out{clustering};
    if (!lod) return out;
    for (const int clusters : {midClusters, farClusters}) {
      ClusteringParams coarse = clustering;
      coarse.clusters = clusters;
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
  // Checks the LoD parameters together and replaces unset coarse cluster counts by K/3 and
  // K/10, so the effective parameters name the counts used.
  void resolve(const std::string& method) {
    if (lod && lodFarPixels >= lodNearPixels)
      throwInputError("{}: parameter 'lod_far_px' ({}) must be below 'lod_near_px' ({})", method,
                      lodFarPixels, lodNearPixels);
    const auto fraction = [&](int divisor) {
      return std::max(1, static_cast<int>(std::lround(double(clustering.clusters) / divisor)));
    };
    if (midClusters == 0) midClusters = fraction(3);
    if (farClusters == 0) farClusters = fraction(10);
    if (midClusters > clustering.clusters)
      throwInputError("{}: parameter 'clusters_mid' ({}) must not exceed 'clusters' ({})", method,
                      midClusters, clustering.clusters);
    if (farClusters > midClusters)
      throwInputError("{}: parameter 'clusters_far' ({}) must not exceed 'clusters_mid' ({})",
                      method, farClusters, midClusters);
  }
};

// A summary of a cloud family for bake reports.
nlohmann::json describeClouds(const std::vector<BillboardCloud>& clouds);

}  // namespace canopy
