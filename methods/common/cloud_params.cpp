#include "methods/common/cloud_params.h"

namespace canopy {

nlohmann::json describeClouds(const std::vector<BillboardCloud>& clouds) {
  nlohmann::json levels = nlohmann::json::array();
  for (const BillboardCloud& cloud : clouds) {
    levels.push_back(
        {{"billboards", cloud.billboards.size()},
         {"mean_plane_distance", cloud.meanPlaneDistance},
         {"max_plane_distance", cloud.maxPlaneDistance},
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
