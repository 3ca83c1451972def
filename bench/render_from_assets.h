#pragma once

#include <filesystem>
#include <string>

#include "common/gl/context.h"

namespace canopy {

// canopy-bench render: one view of a method variant drawn from the asset a run saved when it
// baked it (RUN/assets/<tree>/<variant>/), without baking again — to look at a saved impostor, or
// to check that what was saved is what was measured.
struct RenderFromAssetsRequest {
  std::string config;           // the run's experiment config (trees, variants, view settings)
  std::filesystem::path run;    // the run folder; empty: results/<config name>
  std::string tree;             // tree label, as in the run's records
  std::string variant;          // variant label, as in the run's records
  std::string view;             // view key, as in the run's records and images ("d4_e30_a0")
  std::filesystem::path image;  // the PNG written (composited over the background)
  gl::Backend backend = gl::Backend::kOsMesa;
};

// InputError naming the file for a missing or corrupt asset, a run of another config, or a
// tree, variant or view the config does not have.
void renderFromAssets(const RenderFromAssetsRequest& request);

}  // namespace canopy
