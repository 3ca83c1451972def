#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace canopy {

struct ViewerOptions {
  std::string config;  // take trees and methods from an experiment config
  std::string tree;    // a preset name or a tree file
  int leaves = 0;      // preset leaf count override (0: the preset's)
  std::string method = "polygonal";
  nlohmann::json params = nlohmann::json::object();  // the method's parameters
  int width = 1280, height = 800;
  int forest = 1;          // trees in the forest
  std::string screenshot;  // scripted: render `frames` frames, save this PNG, exit
  int frames = 3;
  bool hideUi = false;          // no ImGui panel (clean screenshots)
  std::string view = "method";  // "method", "split" (reference left) or "error" (heat map)
  bool lit = false;             // two-sided Lambert with the harness's light
  bool shadows = false;         // lit with a shadow map rendered by the method itself
  std::string bookmarks = "canopy_bookmarks.json";
  std::string cameraPath = "canopy_camera_path.json";
};

// Runs the viewer until the window closes (or the scripted screenshot is written). Throws
// InputError for bad input (no display, bad tree file, unknown method or parameter).
void runViewer(const ViewerOptions& options);

}  // namespace canopy
