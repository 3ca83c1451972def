#include "viewer/viewer_ui.h"

#include <imgui.h>

#include <cfloat>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

namespace canopy {
namespace {

void pickers(ViewerPanel& ui) {
  ViewerState& s = ui.state;
  if (ImGui::BeginCombo("tree", s.trees[s.treeIndex].label.c_str())) {
    for (size_t i = 0; i < s.trees.size(); ++i)
      if (ImGui::Selectable(s.trees[i].label.c_str(), i == s.treeIndex) && !ui.bake.busy())
        ui.actions.selectTree(i);
    ImGui::EndCombo();
  }
  if (ImGui::BeginCombo("method", s.methods[s.methodIndex].label.c_str())) {
    for (size_t i = 0; i < s.methods.size(); ++i)
      if (ImGui::Selectable(s.methods[i].label.c_str(), i == s.methodIndex) && !ui.bake.busy())
        ui.actions.selectMethod(i);
    ImGui::EndCombo();
  }
}

// One input per effective parameter, by the type its value has.
void editParams(nlohmann::json& params) {
  for (auto& [key, value] : params.items()) {
    const std::string label = key;
    if (value.is_boolean()) {
      bool b = value;
      if (ImGui::Checkbox(label.c_str(), &b)) value = b;
    } else if (value.is_number_integer()) {
      int i = value;
      if (ImGui::InputInt(label.c_str(), &i)) value = i;
    } else if (value.is_number()) {
      float f = value;
      if (ImGui::InputFloat(label.c_str(), &f, 0.0f, 0.0f, "%.4g")) value = f;
    } else if (value.is_string()) {
      char buffer[128];
      std::snprintf(buffer, sizeof(buffer), "%s", value.get<std::string>().c_str());
      if (ImGui::InputText(label.c_str(), buffer, sizeof(buffer))) value = std::string(buffer);
    } else {
      ImGui::Text("%s = %s", label.c_str(), value.dump().c_str());
    }
  }
}

void parametersAndBake(ViewerPanel& ui) {
  if (ImGui::CollapsingHeader("parameters")) {
    editParams(ui.state.editedParams);
    if (ImGui::Button("re-bake") && !ui.bake.busy()) ui.actions.rebake();
  }
  if (ui.bake.busy()) {
    const float elapsed = float(ui.bake.elapsedSeconds());
    ImGui::ProgressBar(std::fmod(elapsed, 1.0f), ImVec2(-1, 0),
                       fmt::format("baking {}: {:.1f} s", ui.bake.label(), elapsed).c_str());
  } else if (ui.methodReady) {
    ImGui::Text("baked in %.2f s", ui.bake.lastBakeSeconds());
  }
  if (!ui.state.bakeError.empty())
    ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "%s", ui.state.bakeError.c_str());
}

void viewSection(ViewerPanel& ui) {
  if (!ImGui::CollapsingHeader("view", ImGuiTreeNodeFlags_DefaultOpen)) return;
  SceneOptions& scene = ui.state.scene;
  int mode = static_cast<int>(scene.mode);
  ImGui::RadioButton("method", &mode, static_cast<int>(ViewMode::kMethod));
  ImGui::SameLine();
  ImGui::RadioButton("split", &mode, static_cast<int>(ViewMode::kSplit));
  ImGui::SameLine();
  ImGui::RadioButton("error", &mode, static_cast<int>(ViewMode::kError));
  scene.mode = static_cast<ViewMode>(mode);
  if (scene.mode == ViewMode::kSplit) ImGui::SliderFloat("split", &scene.split, 0.0f, 1.0f);
  bool orbit = ui.camera.mode() == CameraController::Mode::kOrbit;
  if (ImGui::Checkbox("orbit (Tab: fly)", &orbit))
    ui.camera.setMode(orbit ? CameraController::Mode::kOrbit : CameraController::Mode::kFly);
  ImGui::SliderFloat("fov", &ui.state.fovY, 10.0f, 100.0f);
  ImGui::Checkbox("wireframe", &scene.wireframe);
  ImGui::SliderInt("force LoD level", &scene.forcedLevel, -1, 6,
                   scene.forcedLevel < 0 ? "auto" : "%d");
  bool lit = ui.render.shading == Shading::kLit;
  if (ImGui::Checkbox("lit", &lit)) ui.render.shading = lit ? Shading::kLit : Shading::kUnlit;
  ImGui::DragFloat3("light", &ui.render.lightDirection.x, 0.01f, -1.0f, 1.0f);
  ImGui::Checkbox("shadows (lit)", &ui.render.shadows);
}

void forestSection(ViewerPanel& ui) {
  if (!ImGui::CollapsingHeader("forest")) return;
  bool changed = ImGui::SliderInt("trees", &ui.state.forestSize, 1, 1000);
  changed |= ImGui::InputInt("layout seed", &ui.state.forestSeed);
  if (changed) ui.actions.relayoutForest();
}

void statsSection(const ViewerPanel& ui) {
  if (!ImGui::CollapsingHeader("stats", ImGuiTreeNodeFlags_DefaultOpen)) return;
  std::vector<float> ms(ui.state.frameMs.begin(), ui.state.frameMs.end());
  const float last = ms.empty() ? 0.0f : ms.back();
  ImGui::Text("%.1f FPS, %.1f ms", last > 0 ? 1000.0f / last : 0.0f, last);
  ImGui::PlotLines("frame ms", ms.data(), int(ms.size()), 0, nullptr, 0.0f, FLT_MAX, ImVec2(0, 50));
  ImGui::Text("memory: %.2f MB texture, %.2f geometry, %.2f other", ui.memory.texture / 1e6,
              ui.memory.geometry / 1e6, ui.memory.other / 1e6);
  ImGui::Text("primitives: %llu, fragments: %llu",
              static_cast<unsigned long long>(ui.drawn.primitives),
              static_cast<unsigned long long>(ui.drawn.fragments));
  ImGui::Text("leaves drawn as polygons: %.1f %%", 100.0 * ui.leafGeometryFraction);
  ImGui::Text("%s", ui.renderer.c_str());
}

void cameraSection(ViewerPanel& ui) {
  if (!ImGui::CollapsingHeader("camera")) return;
  if (ImGui::Button("bookmark (B)")) ui.actions.addBookmark();
  ImGui::SameLine();
  if (ImGui::Button(ui.recording ? "stop recording (R)" : "record path (R)"))
    ui.actions.toggleRecording();
  ImGui::SameLine();
  if (ImGui::Button("screenshot (P)")) ui.actions.saveScreenshot();
  for (size_t i = 0; i < ui.bookmarks; ++i)
    if (ImGui::Button(fmt::format("go to bookmark {}", i + 1).c_str())) ui.actions.goToBookmark(i);
  ImGui::TextWrapped("%s", ui.state.status.c_str());
}

}  // namespace

void drawViewerPanel(ViewerPanel& panel) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Canopy");
  pickers(panel);
  parametersAndBake(panel);
  viewSection(panel);
  forestSection(panel);
  statsSection(panel);
  cameraSection(panel);
  ImGui::End();
}

}  // namespace canopy
