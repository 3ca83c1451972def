#include "viewer/viewer.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <deque>
#include <fstream>
#include <future>
#include <mutex>

#include "bench/experiment.h"
#include "bench/harness.h"
#include "common/atomic_file.h"
#include "common/gl/context.h"
#include "common/image.h"
#include "common/lsystem.h"
#include "common/tree_source.h"
#include "viewer/camera_controller.h"

namespace canopy {
namespace {

using Clock = std::chrono::steady_clock;

// Work the bake thread needs done on the GL thread (photographs of the reference).
class GlTaskQueue {
 public:
  ImageRgbaF run(std::function<ImageRgbaF()> work) {
    std::packaged_task<ImageRgbaF()> task(std::move(work));
    auto result = task.get_future();
    {
      std::lock_guard lock(mMutex);
      mTasks.push_back(std::move(task));
    }
    return result.get();
  }
  void serve() {
    std::deque<std::packaged_task<ImageRgbaF()>> tasks;
    {
      std::lock_guard lock(mMutex);
      tasks.swap(mTasks);
    }
    for (auto& task : tasks) task();
  }

 private:
  std::mutex mMutex;
  std::deque<std::packaged_task<ImageRgbaF()>> mTasks;
};

struct TreeChoice {
  std::string label;
  TreeSpec spec;
};

struct MethodChoice {
  std::string label;
  std::string method;
  nlohmann::json params;
};

class Viewer {
 public:
  explicit Viewer(const ViewerOptions& options) : mOptions(options) {
    // Bad input fails before any window opens.
    collectChoices();
    builtinMethods().find(mMethods[0].method).create(mMethods[0].params, "--params");
    gl::ContextOptions contextOptions;
    contextOptions.backend = gl::Backend::kGlfw;
    contextOptions.visibleWindow = true;
    contextOptions.windowWidth = options.width;
    contextOptions.windowHeight = options.height;
    contextOptions.title = "canopy-view";
    mContext = gl::createContext(contextOptions);
    mWindow = static_cast<GLFWwindow*>(mContext->nativeWindow());
    mDevice = std::make_unique<gl::Device>(mLedger);
    RenderSettings settings;
    settings.supersample = 2;
    settings.shading = options.lit || options.shadows ? Shading::kLit : mConfigShading;
    settings.shadows = options.shadows;
    mHarness = std::make_unique<Harness>(*mDevice, settings);
    mComposite = mDevice->createProgram(
        {gl::embeddedShader("viewer/composite.vert"), gl::embeddedShader("viewer/composite.frag")});
    mEmptyVao = gl::createVertexArray();
    gl::api().BindVertexArray(0);
    mForestSize = options.forest;
    mViewMode = options.view == "split" ? 1 : options.view == "error" ? 2 : 0;
    loadTree(mTreeIndex);
    selectMethod(mMethodIndex, options.params);
    if (!options.hideUi) {
      IMGUI_CHECKVERSION();
      ImGui::CreateContext();
      ImGui::GetIO().IniFilename = nullptr;
      ImGui_ImplGlfw_InitForOpenGL(mWindow, true);
      ImGui_ImplOpenGL3_Init("#version 450 core");
      mImGui = true;
    }
    loadBookmarks();
  }

  ~Viewer() {
    if (mBake.valid()) mBake.wait();
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
      mTasks.serve();
      finishBakeIfReady();
      handleInput(seconds);
      renderScene();
      if (mImGui) drawUi();
      if (!mOptions.screenshot.empty()) {
        // Scripted: wait for the bake, then the requested number of frames.
        if (!mMethod || mBake.valid()) {
          glfwSwapBuffers(mWindow);
          continue;
        }
        if (++frame >= mOptions.frames) {
          writeScreenshot(mOptions.screenshot);
          return;
        }
      }
      mFrameMs.push_back(seconds * 1000.0f);
      if (mFrameMs.size() > 240) mFrameMs.pop_front();
      glfwSwapBuffers(mWindow);
    }
  }

 private:
  void collectChoices() {
    if (!mOptions.config.empty()) {
      const ExperimentConfig config = readExperimentConfig(mOptions.config);
      for (const TreeSpec& spec : config.trees) mTrees.push_back({spec.label(), spec});
      for (const MethodVariant& v : config.variants)
        mMethods.push_back({v.label, v.method, v.params});
      mConfigShading = config.views.render.shading;
    }
    if (!mOptions.tree.empty()) {
      TreeSpec spec;
      const std::filesystem::path path(mOptions.tree);
      if (std::filesystem::exists(path) || path.has_extension() || path.has_parent_path()) {
        if (!std::filesystem::exists(path))
          throwInputError("--tree {}: file not found", path.string());
        spec.kind = TreeSpec::Kind::kFile;
        spec.file.path = mOptions.tree;
      } else {
        treePreset(mOptions.tree);  // InputError naming the unknown preset
        spec.preset = mOptions.tree;
        spec.leaves = mOptions.leaves;
      }
      mTrees.insert(mTrees.begin(), {spec.label(), spec});
    }
    for (const char* preset : {"broadleaf", "shrub", "sparse"}) {
      TreeSpec spec;
      spec.preset = preset;
      mTrees.push_back({spec.label(), spec});
    }
    builtinMethods().find(mOptions.method);  // InputError naming the registered methods
    if (mMethods.empty() || !mOptions.params.empty() || mOptions.method != "polygonal")
      mMethods.insert(mMethods.begin(), {mOptions.method, mOptions.method, mOptions.params});
    for (const std::string& name : builtinMethods().names())
      mMethods.push_back({name, name, nlohmann::json::object()});
  }

  void loadTree(size_t index) {
    if (mBake.valid()) mBake.wait();
    mTreeIndex = index;
    spdlog::info("canopy-view: loading {}", mTrees[index].label);
    mTree = canopy::loadTree(mTrees[index].spec);
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
    layoutTrees();
    if (mMethodIndex < mMethods.size() && mMethod) startBake(mEditedParams);
  }

  void layoutTrees() {
    mForest = layoutForest(mForestSize, mTree.boundingSphereRadius(), mForestSeed);
    mForestBounds = forestBounds(mForest, mTree.bounds);  // the shadow map's extent
    std::vector<glm::mat4> matrices;
    for (const Instance& instance : mForest) matrices.push_back(instance.modelMatrix());
    gl::Device::OwnerScope owner(*mDevice, "viewer");
    mInstanceBuffer = mDevice->createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER, matrices,
                                            "viewer instances");
  }

  void selectMethod(size_t index, const nlohmann::json& params) {
    mMethodIndex = index;
    startBake(params.empty() ? mMethods[index].params : params);
  }

  // Bakes on a worker thread; photographs of the reference are rendered on this (GL) thread.
  void startBake(const nlohmann::json& params) {
    if (mBake.valid()) return;
    mBakeError.clear();
    std::unique_ptr<Method> method;
    try {
      method = builtinMethods().find(mMethods[mMethodIndex].method).create(params, "--params");
    } catch (const InputError& error) {
      if (!mImGui) throw;
      mBakeError = error.what();
      return;
    }
    mBakeStarted = Clock::now();
    mBakingLabel = mMethods[mMethodIndex].label;
    mBake = std::async(std::launch::async, [this, m = std::move(method)]() mutable {
      BakeContext context;
      context.photograph = [this](const Camera& camera, int width, int height) {
        return mTasks.run(
            [=, this] { return mHarness->renderLinearAt(*mReference, camera, width, height); });
      };
      m->bake(mTree, context);
      return std::move(m);
    });
  }

  void finishBakeIfReady() {
    if (!mBake.valid() || mBake.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
      return;
    try {
      std::unique_ptr<Method> baked = mBake.get();
      mMethod.reset();  // release the old method's GPU memory first
      gl::Device::OwnerScope owner(*mDevice, "method");
      baked->upload(*mDevice);
      mMethod = std::move(baked);
      mEditedParams = mMethod->effectiveParams();
      mBakeSeconds = std::chrono::duration<double>(Clock::now() - mBakeStarted).count();
      spdlog::info("canopy-view: {} baked in {:.2f} s", mBakingLabel, mBakeSeconds);
    } catch (const InputError& error) {
      if (!mImGui) throw;
      mBakeError = error.what();
    }
  }

  void handleInput(float seconds) {
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
    float wheel = 0.0f;
    if (mImGui && !uiMouse) wheel = ImGui::GetIO().MouseWheel;
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
      if (pressed(GLFW_KEY_P)) writeScreenshot(fmt::format("canopy_screenshot_{}.png", ++mShots));
      if (pressed(GLFW_KEY_B)) addBookmark();
      if (pressed(GLFW_KEY_R)) toggleRecording();
    }
    mCamera.update(drag, wheel, move, seconds);
    if (mRecording) mPath.push_back(mCamera.camera(mFovY));
  }

  void ensureTargets(int width, int height) {
    if (mMethodTarget.width == width && mMethodTarget.height == height) return;
    gl::Device::OwnerScope owner(*mDevice, "viewer");
    mMethodTarget = mDevice->createRenderTarget(width, height, GL_RGBA16F);
    mReferenceTarget = mDevice->createRenderTarget(width, height, GL_RGBA16F);
  }

  void drawInto(const gl::RenderTarget& target, Method& method, const Camera& camera,
                bool countPrimitives) {
    const gl::Api& g = gl::api();
    FrameContext frame =
        mHarness->makeFrame(camera, {target.width, target.height}, 1, mInstanceBuffer.id());
    frame.forcedLevel = mForcedLevel;
    // The shadow pass (lit, shadows on) renders into its own target, so it comes first.
    mHarness->prepareShadows(method, frame, std::span(mForest), mForestBounds);
    mHarness->beginFrame(target);
    if (mWireframe) g.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    if (countPrimitives) mHarness->statistics().begin();
    method.draw(frame, std::span(mForest));
    if (countPrimitives) {
      mDrawn = mHarness->statistics().end();
      const double leaves = double(mTree.leaves.size()) * double(mForest.size());
      mLeafFraction = leaves > 0 ? double(method.leafPolygonsDrawn()) / leaves : 0.0;
    }
    if (mWireframe) g.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  }

  void renderScene() {
    int width = 0, height = 0;
    glfwGetFramebufferSize(mWindow, &width, &height);
    if (width <= 0 || height <= 0) return;
    ensureTargets(width, height);
    const Camera camera = mCamera.camera(mFovY);
    Method* shown = mMethod ? mMethod.get() : mReference.get();
    drawInto(mMethodTarget, *shown, camera, true);
    if (mViewMode != 0) drawInto(mReferenceTarget, *mReference, camera, false);
    const gl::Api& g = gl::api();
    g.BindFramebuffer(GL_FRAMEBUFFER, 0);
    g.Viewport(0, 0, width, height);
    g.Disable(GL_DEPTH_TEST);
    g.Disable(GL_BLEND);
    mComposite.use();
    mComposite.set("uMethod", 0);
    mComposite.set("uReference", 1);
    mComposite.set("uMode", mViewMode);
    mComposite.set("uSplit", mSplit);
    const glm::vec3 background = mHarness->settings().background;
    mComposite.set("uBackground", glm::vec3(srgbToLinear(background.r), srgbToLinear(background.g),
                                            srgbToLinear(background.b)));
    g.ActiveTexture(GL_TEXTURE0);
    g.BindTexture(GL_TEXTURE_2D, mMethodTarget.color.id());
    g.ActiveTexture(GL_TEXTURE1);
    g.BindTexture(GL_TEXTURE_2D, (mViewMode ? mReferenceTarget : mMethodTarget).color.id());
    g.ActiveTexture(GL_TEXTURE0);
    g.BindVertexArray(mEmptyVao.id());
    g.DrawArrays(GL_TRIANGLES, 0, 3);
    g.BindVertexArray(0);
  }

  void editParams() {
    for (auto& [key, value] : mEditedParams.items()) {
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

  void drawUi() {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(360, 0), ImGuiCond_FirstUseEver);
    ImGui::Begin("Canopy");
    if (ImGui::BeginCombo("tree", mTrees[mTreeIndex].label.c_str())) {
      for (size_t i = 0; i < mTrees.size(); ++i)
        if (ImGui::Selectable(mTrees[i].label.c_str(), i == mTreeIndex) && !mBake.valid())
          loadTree(i);
      ImGui::EndCombo();
    }
    if (ImGui::BeginCombo("method", mMethods[mMethodIndex].label.c_str())) {
      for (size_t i = 0; i < mMethods.size(); ++i)
        if (ImGui::Selectable(mMethods[i].label.c_str(), i == mMethodIndex) && !mBake.valid())
          selectMethod(i, nlohmann::json::object());
      ImGui::EndCombo();
    }
    if (ImGui::CollapsingHeader("parameters")) {
      editParams();
      if (ImGui::Button("re-bake") && !mBake.valid()) startBake(mEditedParams);
    }
    if (mBake.valid()) {
      const float elapsed = std::chrono::duration<float>(Clock::now() - mBakeStarted).count();
      ImGui::ProgressBar(std::fmod(elapsed, 1.0f), ImVec2(-1, 0),
                         fmt::format("baking {}: {:.1f} s", mBakingLabel, elapsed).c_str());
    } else if (mMethod) {
      ImGui::Text("baked in %.2f s", mBakeSeconds);
    }
    if (!mBakeError.empty()) ImGui::TextColored(ImVec4(1, 0.3f, 0.3f, 1), "%s", mBakeError.c_str());
    if (ImGui::CollapsingHeader("view", ImGuiTreeNodeFlags_DefaultOpen)) {
      ImGui::RadioButton("method", &mViewMode, 0);
      ImGui::SameLine();
      ImGui::RadioButton("split", &mViewMode, 1);
      ImGui::SameLine();
      ImGui::RadioButton("error", &mViewMode, 2);
      if (mViewMode == 1) ImGui::SliderFloat("split", &mSplit, 0.0f, 1.0f);
      bool orbit = mCamera.mode() == CameraController::Mode::kOrbit;
      if (ImGui::Checkbox("orbit (Tab: fly)", &orbit))
        mCamera.setMode(orbit ? CameraController::Mode::kOrbit : CameraController::Mode::kFly);
      ImGui::SliderFloat("fov", &mFovY, 10.0f, 100.0f);
      ImGui::Checkbox("wireframe", &mWireframe);
      ImGui::SliderInt("force LoD level", &mForcedLevel, -1, 6, mForcedLevel < 0 ? "auto" : "%d");
      bool lit = mHarness->settings().shading == Shading::kLit;
      if (ImGui::Checkbox("lit", &lit))
        mHarness->settings().shading = lit ? Shading::kLit : Shading::kUnlit;
      ImGui::DragFloat3("light", &mHarness->settings().lightDirection.x, 0.01f, -1.0f, 1.0f);
      ImGui::Checkbox("shadows (lit)", &mHarness->settings().shadows);
    }
    if (ImGui::CollapsingHeader("forest")) {
      bool changed = ImGui::SliderInt("trees", &mForestSize, 1, 1000);
      changed |= ImGui::InputInt("layout seed", reinterpret_cast<int*>(&mForestSeed));
      if (changed) layoutTrees();
    }
    if (ImGui::CollapsingHeader("stats", ImGuiTreeNodeFlags_DefaultOpen)) {
      std::vector<float> ms(mFrameMs.begin(), mFrameMs.end());
      const float last = ms.empty() ? 0.0f : ms.back();
      ImGui::Text("%.1f FPS, %.1f ms", last > 0 ? 1000.0f / last : 0.0f, last);
      ImGui::PlotLines("frame ms", ms.data(), int(ms.size()), 0, nullptr, 0.0f, FLT_MAX,
                       ImVec2(0, 50));
      const gl::MemoryTotals memory = mLedger.totals("method");
      ImGui::Text("memory: %.2f MB texture, %.2f geometry, %.2f other", memory.texture / 1e6,
                  memory.geometry / 1e6, memory.other / 1e6);
      ImGui::Text("primitives: %llu, fragments: %llu",
                  static_cast<unsigned long long>(mDrawn.primitives),
                  static_cast<unsigned long long>(mDrawn.fragments));
      ImGui::Text("leaves drawn as polygons: %.1f %%", 100.0 * mLeafFraction);
      ImGui::Text("%s", mContext->renderer().c_str());
    }
    if (ImGui::CollapsingHeader("camera")) {
      if (ImGui::Button("bookmark (B)")) addBookmark();
      ImGui::SameLine();
      if (ImGui::Button(mRecording ? "stop recording (R)" : "record path (R)")) toggleRecording();
      ImGui::SameLine();
      if (ImGui::Button("screenshot (P)"))
        writeScreenshot(fmt::format("canopy_screenshot_{}.png", ++mShots));
      for (size_t i = 0; i < mBookmarks.size(); ++i) {
        if (ImGui::Button(fmt::format("go to bookmark {}", i + 1).c_str())) {
          try {
            mCamera.fromJson(mBookmarks[i]);
          } catch (const nlohmann::json::exception&) {
          }
        }
      }
      ImGui::TextWrapped("%s", mStatus.c_str());
    }
    ImGui::End();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }

  void loadBookmarks() {
    std::ifstream in(mOptions.bookmarks);
    if (!in) return;
    try {
      mBookmarks = nlohmann::json::parse(in).at("bookmarks").get<std::vector<nlohmann::json>>();
    } catch (const nlohmann::json::exception& e) {
      throwInputError("{}: not a bookmarks file ({})", mOptions.bookmarks, e.what());
    }
  }

  void addBookmark() {
    mBookmarks.push_back(mCamera.toJson());
    writeTextAtomically(mOptions.bookmarks, nlohmann::json({{"bookmarks", mBookmarks}}).dump(2));
    mStatus = fmt::format("bookmark {} saved to {}", mBookmarks.size(), mOptions.bookmarks);
  }

  // The recorded path, as canopy-bench replays it ("forests": {"camera_path": FILE}).
  void toggleRecording() {
    mRecording = !mRecording;
    if (mRecording) {
      mPath.clear();
      mStatus = "recording the camera path";
      return;
    }
    nlohmann::json frames = nlohmann::json::array();
    for (const Camera& c : mPath)
      frames.push_back({{"position", {c.position.x, c.position.y, c.position.z}},
                        {"target", {c.target.x, c.target.y, c.target.z}},
                        {"up", {c.up.x, c.up.y, c.up.z}},
                        {"fov_deg", c.fovYDegrees}});
    writeTextAtomically(mOptions.cameraPath,
                        nlohmann::json({{"tree", mTrees[mTreeIndex].label},
                                        {"units", "world units of the tree at the origin"},
                                        {"frames", frames}})
                            .dump(1));
    mStatus = fmt::format("{} frames saved to {}", mPath.size(), mOptions.cameraPath);
  }

  void writeScreenshot(const std::string& path) {
    int width = 0, height = 0;
    glfwGetFramebufferSize(mWindow, &width, &height);
    ImageRgbaF pixels(width, height);
    const gl::Api& g = gl::api();
    g.BindFramebuffer(GL_FRAMEBUFFER, 0);
    g.ReadBuffer(GL_BACK);
    g.PixelStorei(GL_PACK_ALIGNMENT, 4);
    g.ReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.pixels.data());
    flipRows(pixels);
    ImageRgba8 image(width, height);
    for (size_t i = 0; i < image.pixels.size(); ++i)
      image.pixels[i] = uint8_t(std::lround(std::clamp(pixels.pixels[i], 0.0f, 1.0f) * 255.0f));
    writePng(path, withOpaqueAlpha(image));
    mStatus = "screenshot " + path;
    spdlog::info("canopy-view: {}", mStatus);
  }

  ViewerOptions mOptions;
  std::unique_ptr<gl::Context> mContext;
  GLFWwindow* mWindow = nullptr;
  gl::Ledger mLedger;
  std::unique_ptr<gl::Device> mDevice;
  std::unique_ptr<Harness> mHarness;
  gl::Program mComposite;
  gl::VertexArray mEmptyVao;
  gl::DrawCounts mDrawn;       // of the shown method's last frame
  double mLeafFraction = 0.0;  // its leaf_geometry_fraction
  bool mImGui = false;
  Shading mConfigShading = Shading::kUnlit;

  std::vector<TreeChoice> mTrees;
  std::vector<MethodChoice> mMethods;
  size_t mTreeIndex = 0, mMethodIndex = 0;
  Tree mTree;
  std::unique_ptr<Method> mReference, mMethod;
  nlohmann::json mEditedParams = nlohmann::json::object();
  std::future<std::unique_ptr<Method>> mBake;
  GlTaskQueue mTasks;
  Clock::time_point mBakeStarted;
  std::string mBakingLabel, mBakeError, mStatus;
  double mBakeSeconds = 0.0;

  std::vector<Instance> mForest;
  Aabb mForestBounds;  // of the forest, for the shadow map; updated with the layout
  int mForestSize = 1;
  uint32_t mForestSeed = 1;
  gl::Buffer mInstanceBuffer;
  gl::RenderTarget mMethodTarget, mReferenceTarget;

  CameraController mCamera;
  float mFovY = 40.0f;
  int mViewMode = 0;
  float mSplit = 0.5f;
  bool mWireframe = false;
  int mForcedLevel = -1;
  std::deque<float> mFrameMs;
  glm::dvec2 mLastCursor{0.0};
  bool mWasDragging = false;
  std::map<int, bool> mKeysDown;
  std::vector<nlohmann::json> mBookmarks;
  bool mRecording = false;
  std::vector<Camera> mPath;
  int mShots = 0;
};

}  // namespace

void runViewer(const ViewerOptions& options) {
  Viewer viewer(options);
  viewer.run();
}

}  // namespace canopy
