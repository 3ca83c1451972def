#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/budget.h"
#include "bench/harness.h"
#include "bench/popping.h"
#include "common/tree_source.h"

namespace canopy {

// One method with one value for every parameter (a point of a sweep).
struct MethodVariant {
  std::string method;
  nlohmann::json params = nlohmann::json::object();  // as configured (scalars only)
  std::string label;  // "polygonal", "billboard_cloud[clusters=200,density=64]"
};

// "views.closeups": a ring seen through a narrow field of view from outside the crown, so that a
// leaf spans tens of pixels (the scale of the multi-layer paper's Fig. 13). Scored like every
// view; its records say "ring": "closeup".
struct CloseupSettings {
  bool enabled = false;  // the config has "closeups"
  float distance = 1.5f;
  float fovYDegrees = 8.0f;
  int azimuths = 4;
  std::vector<float> elevations{0.0f, 30.0f};

  template <class V>
  void visit(V& v) {
    v("distance", distance, 1.01f, 10000.0f, "bounding-sphere radii from the centre");
    v("fov_deg", fovYDegrees, 0.5f, 170.0f, "vertical field of view");
    v("azimuths", azimuths, 1, 360, "views evenly spaced about the up axis");
    v("elevations", elevations, -90.0f, 90.0f, "degrees above the horizon");
  }
};

// The config's "views": how images are made (RenderSettings) and the orbit rings.
struct ViewSettings {
  RenderSettings render;
  std::vector<float> distances{1.5f, 4.0f, 12.0f};
  std::vector<float> elevations{0.0f, 30.0f, 60.0f, 90.0f};
  int azimuths = 8;
  CloseupSettings closeups;

  template <class V>
  void visit(V& v) {
    render.visit(v);
    v("distances", distances, 1.01f, 10000.0f, "orbit rings, in bounding-sphere radii");
    v("elevations", elevations, -90.0f, 90.0f, "degrees above the horizon (90: top views)");
    v("azimuths", azimuths, 1, 360, "views per ring and elevation, evenly spaced");
  }
};

// The config's "forests": the sizes, the timing, and "camera_path" (a path recorded in
// canopy-view, replayed instead of the orbit).
struct ForestSettings {
  std::vector<int> sizes{1, 10, 100};
  ForestTiming timing;
  // Forests so large that the reference takes tens of seconds a frame (10,000 polygonal trees on
  // a software renderer) are timed on a shorter path: every camera is still drawn by the
  // reference and each method in turn, only fewer cameras (the records say how many).
  int largeFrom = 0;
  int largeFrames = 2;
  int largeWarmup = 1;

  // The timing of a forest of `trees`: `timing`, or its shorter path from large_from on.
  ForestTiming timingFor(int trees) const;

  template <class V>
  void visit(V& v) {
    v("sizes", sizes, 1, 1'000'000, "trees per forest, each timed and scored");
    timing.visit(v);
    v("large_from", largeFrom, 0, 1'000'000,
      "forests of at least this many trees are timed on large_frames cameras after "
      "large_warmup untimed frames, in one block (0: none)");
    v("large_frames", largeFrames, 1, 100'000, "timed frames of each for large forests");
    v("large_warmup", largeWarmup, 0, 100'000, "untimed frames of each before, large forests");
  }
};

struct ExperimentConfig {
  std::string name;
  uint64_t seed = 1;
  std::vector<TreeSpec> trees;
  std::vector<MethodVariant> variants;
  ViewSettings views;
  ForestSettings forests;
  PoppingSettings popping;               // enabled when the config has "popping"
  std::optional<BudgetSettings> budget;  // the config's "budget", if any
  nlohmann::json raw;                    // the config as read
  std::string hash;                      // of its canonical form
};

// Parses and validates a whole config; every unknown key or out-of-range value is an InputError
// naming the key. `baseDirectory` resolves relative tree files (the config's folder).
ExperimentConfig parseExperimentConfig(const nlohmann::json& json,
                                       const std::string& baseDirectory);
ExperimentConfig readExperimentConfig(const std::string& path);

// A list where a parameter takes one value is a sweep: the cartesian product of all lists, in
// key order. Scalars pass through.
std::vector<nlohmann::json> expandSweep(const nlohmann::json& params);

// FNV-1a 64 of the canonical JSON text, as "fnv1a64:<hex>".
std::string hashJson(const nlohmann::json& json);

}  // namespace canopy
