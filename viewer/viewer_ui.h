#pragma once

#include <deque>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/harness.h"
#include "common/gl/ledger.h"
#include "common/tree_source.h"
#include "viewer/bake_worker.h"
#include "viewer/camera_controller.h"
#include "viewer/scene_renderer.h"

namespace canopy {

struct TreeChoice {
  std::string label;
  TreeSpec spec;
};

struct MethodChoice {
  std::string label;
  std::string method;
  nlohmann::json params;
};

// What the viewer offers and what its panel edits.
struct ViewerState {
  std::vector<TreeChoice> trees;
  std::vector<MethodChoice> methods;
  size_t treeIndex = 0, methodIndex = 0;
  nlohmann::json editedParams = nlohmann::json::object();  // the shown method's, editable
  std::string bakeError;                                   // the last bake's, shown in red
  std::string status;                                      // the last action's line
  SceneOptions scene;
  float fovY = 40.0f;
  int forestSize = 1;
  int forestSeed = 1;
  std::deque<float> frameMs;  // the last frames' times, for the graph
};

// What the panel's buttons and pickers do (the viewer implements them).
class ViewerActions {
 public:
  virtual ~ViewerActions() = default;
  virtual void selectTree(size_t index) = 0;
  virtual void selectMethod(size_t index) = 0;
  virtual void rebake() = 0;
  virtual void relayoutForest() = 0;
  virtual void addBookmark() = 0;
  virtual void goToBookmark(size_t index) = 0;
  virtual void toggleRecording() = 0;
  virtual void saveScreenshot() = 0;
};

// Everything one frame of the panel reads or edits.
struct ViewerPanel {
  ViewerState& state;
  ViewerActions& actions;
  CameraController& camera;
  RenderSettings& render;  // shading, light and shadows are edited live
  const BakeWorker& bake;
  bool methodReady = false;
  gl::MemoryTotals memory;  // the shown method's ledger memory
  gl::DrawCounts drawn;
  double leafGeometryFraction = 0.0;
  std::string renderer;
  size_t bookmarks = 0;
  bool recording = false;
};

// Dear ImGui: the panel for one frame (between NewFrame and Render).
void drawViewerPanel(ViewerPanel& panel);

}  // namespace canopy
