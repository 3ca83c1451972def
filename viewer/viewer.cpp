#include "viewer/viewer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <map>

#include <fmt/format.h>

#include "bench/experiment.h"
#include "bench/harness.h"
#include "common/gl/context.h"
#include "common/image.h"
#include "common/lsystem.h"
#include "common/tree_source.h"
#include "viewer/bake_worker.h"
#include "viewer/camera_controller.h"
#include "viewer/camera_recorder.h"
#include "viewer/scene_renderer.h"
#include "viewer/viewer_ui.h"

namespace canopy {
namespace {

using Clock = std::chrono::steady_clock;

// The trees and method variants the pickers offer: the config's, the command line's, and every
// preset and registered method.
void collectChoices(const ViewerOptions& options, ViewerState& state, Shading& configShading) {
  if (!options.config.empty()) {
    const ExperimentConfig config = readExperimentConfig(options.config);
    for (const TreeSpec& spec : config.trees) state.trees.push_back({spec.label(), spec});
    for (const MethodVariant& v : config.variants)
      state.methods.push_back({v.label, v.method, v.params});
    configShading = config.views.render.shading;
  }
  if (!options.tree.empty()) {
    TreeSpec spec;
    const std::filesystem::path path(options.tree);
    if (std::filesystem::exists(path) || path.has_extension() || path.has_parent_path()) {
      if (!std::filesystem::exists(path))
        throwInputError("--tree {}: file not found", path.string());
      spec.kind = TreeSpec::Kind::kFile;
      spec.file.path = options.tree;
    } else {
      treePreset(options.tree);  // InputError naming the unknown preset
      spec.preset = options.tree;
      spec.leaves = options.leaves;
    }
    state.trees.insert(state.trees.begin(), {spec.label(), spec});
  }
  for (const std::string& preset : treePresetNames()) {
    TreeSpec spec;
    spec.preset = preset;
    state.trees.push_back({spec.label(), spec});
  }
  builtinMethods().find(options.method);  // InputError naming the registered methods
  if (state.methods.empty() || !options.params.empty() || options.method != "polygonal")
    state.methods.insert(state.methods.begin(), {options.method, options.method, options.params});
  for (const std::string& name : builtinMethods().names())
    state.methods.push_back({name, name, nlohmann::json::object()});
}

class Viewer final : public ViewerActions {
 public:
  explicit Viewer(const ViewerOptions& options)
      : mOptions(options), mRecorder(options.bookmarks, options.cameraPath) {
    // Bad input fails before any window opens.
    Shading configShading = Shading::kUnlit;
    collectChoices(options, mState, configShading);
    builtinMethods().find(mState.methods[0].method).create(mState.methods[0].params, "--params");
    mState.scene.mode = parseViewMode(options.view);
    mState.forestSize = options.forest;
    openWindow(configShading);
    loadTree(mState.treeIndex);
    startBake(options.params.empty() ? mState.methods[0].params : options.params);
    if (!options.hideUi) initUi();
    mRecorder.loadBookmarks();
  }

  ~Viewer() override {
    mBake.wait();
    if (mImGui) {
      ImGui_ImplOpenGL3_Shutdown();
      ImGui_ImplGlfw_Shutdown();
      ImGui::DestroyContext();
    }
  }

  void run() {
    int frame = 0;
    auto last = Clock::now();
    while (!glfwWindowShouldClose(mWindow)) {
      glfwPollEvents();
      const auto now = Clock::now();
      const float seconds = std::chrono::duration<float>(now - last).count();
      last = now;
      finishBake();
      handleInput(seconds);
      renderFrame();
      // Scripted: wait for the bake, then the requested number of frames.
      const bool ready = mMethod && !mBake.busy();
      if (!mOptions.screenshot.empty() && ready && ++frame >= mOptions.frames) {
        writeScreenshot(mOptions.screenshot);
        return;
      }
      if (ready) {
        mState.frameMs.push_back(seconds * 1000.0f);
        if (mState.frameMs.size() > 240) mState.frameMs.pop_front();
      }
      glfwSwapBuffers(mWindow);
    }
  }

  // ViewerActions, for the panel.
  void selectTree(size_t index) override { loadTree(index); }
  void selectMethod(size_t index) override {
    mState.methodIndex = index;
    startBake(mState.methods[index].params);
  }
  void rebake() override { startBake(mState.editedParams); }
  void relayoutForest() override { layoutForest(); }
  void addBookmark() override { mState.status = mRecorder.addBookmark(mCamera); }
  void goToBookmark(size_t index) override {
    if (!mRecorder.goTo(index, mCamera)) mState.status = "that bookmark is malformed";
  }
  void toggleRecording() override {
    mState.status = mRecorder.toggleRecording(mState.trees[mState.treeIndex].label);
  }
  void saveScreenshot() override {
    writeScreenshot(fmt::format("canopy_screenshot_{}.png", ++mShots));
  }

 private:
  void openWindow(Shading configShading) {
    gl::ContextOptions contextOptions;
    contextOptions.backend = gl::Backend::kGlfw;
    contextOptions.visibleWindow = true;
    contextOptions.windowWidth = mOptions.width;
    contextOptions.windowHeight = mOptions.height;
    contextOptions.title = "canopy-view";
    mContext = gl::createContext(contextOptions);
    mWindow = static_cast<GLFWwindow*>(mContext->nativeWindow());
    mDevice = std::make_unique<gl::Device>(mLedger);
    RenderSettings settings;
    settings.supersample = 2;
    settings.shading = mOptions.lit || mOptions.shadows ? Shading::kLit : configShading;
    settings.shadows = mOptions.shadows;
    mHarness = std::make_unique<Harness>(*mDevice, settings);
    mScene = std::make_unique<SceneRenderer>(*mDevice, *mHarness);
  }

  void initUi() {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui_ImplGlfw_InitForOpenGL(mWindow, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
    mImGui = true;
  }

  void loadTree(size_t index) {
    mBake.wait();
    mState.treeIndex = index;
    spdlog::info("canopy-view: loading {}", mState.trees[index].label);
    mTree = canopy::loadTree(mState.trees[index].spec);
    if (mTree.captures) throwInputError("canopy-view: capture folders have no mesh to show");
    mCamera.frameTree(mTree.bounds);
    // The reference, for the split view, the error map and photographs.
    mReference = builtinMethods().find("polygonal").create(nlohmann::json::object(), "viewer");
    BakeContext context;
    mReference->bake(mTree, context);
    {
      gl::Device::OwnerScope owner(*mDevice, "reference");
      mReference->upload(*mDevice);
    }
    mHarness->setTree(mTree.bounds, mTree.leaves.size());
    layoutForest();
    if (mMethod) startBake(mState.editedParams);
  }

  void layoutForest() {
    mForest.instances = canopy::layoutForest(mState.forestSize, mTree.boundingSphereRadius(),
                                             static_cast<uint64_t>(mState.forestSeed));
    mForest.bounds = forestBounds(mForest.instances, mTree.bounds);  // the shadow map's extent
    std::vector<glm::mat4> matrices;
    for (const Instance& instance : mForest.instances) matrices.push_back(instance.modelMatrix());
    gl::Device::OwnerScope owner(*mDevice, "viewer");
    mForest.matrices = mDevice->createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER, matrices,
                                             "viewer instances");
  }

  // Bakes on the worker; photographs of the reference are rendered on this (GL) thread.
  void startBake(const nlohmann::json& params) {
    if (mBake.busy()) return;
    mState.bakeError.clear();
    const MethodChoice& choice = mState.methods[mState.methodIndex];
    std::unique_ptr<Method> method;
    try {
      method = builtinMethods().find(choice.method).create(params, "--params");
    } catch (const InputError& error) {
      if (!mImGui) throw;
      mState.bakeError = error.what();
      return;
    }
    mBake.start(std::move(method), mTree, choice.label,
                [this](const Camera& camera, int width, int height) {
                  return mHarness->renderLinearAt(*mReference, camera, width, height);
                });
  }

  void finishBake() {
    try {
      std::unique_ptr<Method> baked = mBake.poll();
      if (!baked) return;
      mMethod.reset();  // release the old method's GPU memory first
      gl::Device::OwnerScope owner(*mDevice, "method");
      baked->upload(*mDevice);
      mMethod = std::move(baked);
      mState.editedParams = mMethod->effectiveParams();
      spdlog::info("canopy-view: {} baked in {:.2f} s", mBake.label(), mBake.lastBakeSeconds());
    } catch (const InputError& error) {
      if (!mImGui) throw;
      mState.bakeError = error.what();
    }
  }

  void handleInput(float seconds);
  void renderFrame();
  void writeScreenshot(const std::string& path);

  ViewerOptions mOptions;
  ViewerState mState;
  std::unique_ptr<gl::Context> mContext;
  GLFWwindow* mWindow = nullptr;
  gl::Ledger mLedger;
  std::unique_ptr<gl::Device> mDevice;
  std::unique_ptr<Harness> mHarness;
  std::unique_ptr<SceneRenderer> mScene;
  bool mImGui = false;
  Tree mTree;
  std::unique_ptr<Method> mReference, mMethod;
  ViewerForest mForest;
  CameraController mCamera;
  CameraRecorder mRecorder;
  glm::dvec2 mLastCursor{0.0};
  bool mWasDragging = false;
  std::map<int, bool> mKeysDown;
  int mShots = 0;
  BakeWorker mBake;  // last: destroyed first, while the GL pieces its photographs use still live
};

void Viewer::handleInput(float seconds) {
  const bool uiMouse = mImGui && ImGui::GetIO().WantCaptureMouse;
  const bool uiKeys = mImGui && ImGui::GetIO().WantCaptureKeyboard;
  double x = 0, y = 0;
  glfwGetCursorPos(mWindow, &x, &y);
  glm::vec2 drag(0.0f);
  const bool dragging =
      !uiMouse && (glfwGetMouseButton(mWindow, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS ||
                   glfwGetMouseButton(mWindow, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS);
  if (dragging && mWasDragging)
    drag = glm::vec2(float(x - mLastCursor.x), float(y - mLastCursor.y));
  mWasDragging = dragging;
  mLastCursor = {x, y};
  const float wheel = mImGui && !uiMouse ? ImGui::GetIO().MouseWheel : 0.0f;
  glm::vec3 move(0.0f);
  if (!uiKeys) {
    const auto key = [&](int k) { return glfwGetKey(mWindow, k) == GLFW_PRESS ? 1.0f : 0.0f; };
    move = {key(GLFW_KEY_D) - key(GLFW_KEY_A), key(GLFW_KEY_E) - key(GLFW_KEY_Q),
            key(GLFW_KEY_W) - key(GLFW_KEY_S)};
    const auto pressed = [&](int k) {
      const bool down = glfwGetKey(mWindow, k) == GLFW_PRESS;
      const bool edge = down && !mKeysDown[k];
      mKeysDown[k] = down;
      return edge;
    };
    if (pressed(GLFW_KEY_TAB))
      mCamera.setMode(mCamera.mode() == CameraController::Mode::kOrbit
                          ? CameraController::Mode::kFly
                          : CameraController::Mode::kOrbit);
    if (pressed(GLFW_KEY_P)) saveScreenshot();
    if (pressed(GLFW_KEY_B)) addBookmark();
    if (pressed(GLFW_KEY_R)) toggleRecording();
  }
  mCamera.update(drag, wheel, move, seconds);
  mRecorder.record(mCamera.camera(mState.fovY));
}

void Viewer::renderFrame() {
  int width = 0, height = 0;
  glfwGetFramebufferSize(mWindow, &width, &height);
  Method& shown = mMethod ? *mMethod : *mReference;
  mScene->render(shown, *mReference, mCamera.camera(mState.fovY), mForest, mTree.leaves.size(),
                 {width, height}, mState.scene);
  if (!mImGui) return;
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  ViewerPanel panel{mState,
                    *this,
                    mCamera,
                    mHarness->settings(),
                    mBake,
                    mMethod != nullptr,
                    mLedger.totals("method"),
                    mScene->drawn(),
                    mScene->leafGeometryFraction(),
                    mContext->renderer(),
                    mRecorder.bookmarkCount(),
                    mRecorder.recording()};
  drawViewerPanel(panel);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void Viewer::writeScreenshot(const std::string& path) {
  int width = 0, height = 0;
  glfwGetFramebufferSize(mWindow, &width, &height);
  const std::filesystem::path file(path);
  if (file.has_parent_path() && !std::filesystem::is_directory(file.parent_path()))
    throwInputError("--screenshot {}: the folder {} does not exist", path,
                    file.parent_path().string());
  writePng(file, mScene->screenshot({width, height}));
  mState.status = "screenshot " + path;
  spdlog::info("canopy-view: {}", mState.status);
}

}  // namespace

void runViewer(const ViewerOptions& options) {
  Viewer viewer(options);
  viewer.run();
}

}  // namespace canopy
