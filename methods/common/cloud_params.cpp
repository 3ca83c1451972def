#include "methods/common/cloud_params.h"

namespace canopy {

nlohmann::json describeClouds(const std::vector<BillboardCloud>& clouds) {
  nlohmann::json levels = nlohmann::json::array();
  for (const BillboardCloud& cloud : clouds) {
    levels.push_back(
        {{"billboards", cloud.billboards.size()},
         {"clusters", cloud.clusters},
         {"mean_plane_distance", cloud.meanPlaneDistance},
         {"max_plane_distance", cloud.maxPlaneDistance},
         {"mean_alignment", cloud.meanAlignment},
         {"mean_corner_distance_leaf_lengths",
          cloud.meanLeafLength > 0 ? cloud.meanPlaneDistance / cloud.meanLeafLength : 0.0f},
         {"quad_area", cloud.quadArea},
         {"projected_leaf_area", cloud.projectedLeafArea},
         {"quad_to_leaf_area",
          cloud.projectedLeafArea > 0 ? cloud.quadArea / cloud.projectedLeafArea : 0.0},
         {"iterations", cloud.iterationsRun},
         {"clustering_s", cloud.seconds}});
  }
  return levels;
}

}  // namespace canopy
