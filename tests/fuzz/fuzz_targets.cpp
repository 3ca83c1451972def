#include "fuzz_targets.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include <spdlog/spdlog.h>

#include "bench/experiment.h"
#include "bench/run_names.h"
#include "bench/runner.h"
#include "common/camera_path.h"
#include "common/captures.h"
#include "common/config.h"
#include "common/error.h"
#include "common/image.h"
#include "common/progress.h"
#include "common/tree_loader.h"
#include "methods/method.h"

namespace canopy::fuzz {

namespace fs = std::filesystem;

namespace {

// A scratch folder per process, in memory where the system has it (the targets write a file per
// input), removed at exit.
class ScratchFolder {
 public:
  ScratchFolder() {
    const fs::path base =
        fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    mPath = base / ("canopy_fuzz_" + std::to_string(::getpid()));
    fs::create_directories(mPath);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(mPath, ignored);
  }
  const fs::path& path() const { return mPath; }

 private:
  fs::path mPath;
};

const fs::path& scratch() {
  static ScratchFolder folder;
  return folder.path();
}

void writeBytes(const fs::path& path, const uint8_t* data, size_t size) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

void writeText(const fs::path& path, const std::string& text) {
  writeBytes(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

// Runs a reader; a bad input must end in an InputError, which is the right answer.
template <typename Reader>
void expectNoBug(Reader&& reader) {
  try {
    reader();
  } catch (const InputError&) {
  }
}

void quietLogs() {
  static const bool done = [] {
    spdlog::set_level(spdlog::level::off);
    ProgressBar::setEnabled(false);
    return true;
  }();
  (void)done;
}

// A leaf texture with a transparent border, as a model's texture would be.
ImageRgba8 leafImage() {
  ImageRgba8 image(8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      uint8_t* p = image.at(x, y);
      p[0] = 40, p[1] = 160, p[2] = 30, p[3] = (x >= 2 && x < 6) ? 255 : 0;
    }
  return image;
}

}  // namespace

void runConfig(const uint8_t* data, size_t size) {
  quietLogs();
  const std::string text(reinterpret_cast<const char*>(data), size);
  expectNoBug([&] { parseExperimentConfig(parseJson(text, "fuzz.json"), scratch().string()); });
}

void runTreeLoader(const uint8_t* data, size_t size) {
  quietLogs();
  static const fs::path folder = [] {
    const fs::path f = scratch() / "tree";
    writePng(f / "leaf.png", leafImage());
    writeText(f / "tree.mtl",
              "newmtl bark\nKd 0.3 0.2 0.1\nnewmtl leaf\nmap_Kd leaf.png\n"
              "map_d leaf.png\n");
    return f;
  }();
  if (size == 0) return;
  static const char* const kExtensions[] = {".obj", ".gltf", ".glb"};
  const fs::path model = folder / (std::string("model") + kExtensions[data[0] % 3]);
  writeBytes(model, data + 1, size - 1);
  expectNoBug([&] { loadTreeFile({model.string()}); });
  fs::remove(model);
}

void runCaptures(const uint8_t* data, size_t size) {
  quietLogs();
  static const fs::path folder = [] {
    const fs::path f = scratch() / "captures";
    // Four train and two test views of an opaque square, cameras on a ring looking at the origin.
    std::vector<CapturedView> train, test;
    Aabb bounds;
    bounds.min = glm::vec3(-1.0f);
    bounds.max = glm::vec3(1.0f);
    for (int i = 0; i < 6; ++i) {
      CapturedView view{orbitCamera(bounds, {4.0f, 20.0f, 60.0f * i}, 40.0f), ImageRgbaF(16, 16),
                        ""};
      for (int y = 5; y < 11; ++y)
        for (int x = 5; x < 11; ++x) view.image.at(x, y)[3] = view.image.at(x, y)[1] = 1.0f;
      (i < 4 ? train : test).push_back(view);
    }
    writeNerfCaptures(f, train, test);
    return f;
  }();
  writeBytes(folder / "transforms_train.json", data, size);
  expectNoBug([&] { readNerfCaptures(folder); });
}

void runCameraPath(const uint8_t* data, size_t size) {
  quietLogs();
  const fs::path path = scratch() / "camera_path.json";
  writeBytes(path, data, size);
  expectNoBug([&] { readCameraPath(path); });
}

namespace {

// One baked asset per registered method, of a tiny tree at small settings (the bake runs once,
// under the sanitizers), saved by the runner as a run saves it.
struct BakedAssets {
  std::vector<std::string> methods;
  std::vector<nlohmann::json> params;  // what each was baked with (load may check them)
  std::vector<fs::path> folders;
  std::vector<std::vector<fs::path>> files;  // each folder's files, sorted
};

nlohmann::json smallParams(const std::string& method) {
  if (method == "billboard_cloud" || method == "single_leaf_indirect" ||
      method == "multilayer_indirect")
    return {{"clusters", 20}};
  if (method == "bbox_hierarchy") return {{"texture_size", 16}};
  if (method == "volumetric_opacity")
    return {{"views", 6}, {"capture_resolution", 64}, {"level", 2}};
  return nlohmann::json::object();
}

const BakedAssets& bakedAssets() {
  static const BakedAssets assets = [] {
    BakedAssets result;
    const fs::path run = scratch() / "assets_run";
    nlohmann::json methods = nlohmann::json::array();
    for (const std::string& name : builtinMethods().names())
      methods.push_back({{"method", name}, {"params", smallParams(name)}});
    nlohmann::json config = parseJson(
        R"({"name": "fuzz", "trees": [{"preset": "sparse", "seed": 2, "leaves": 100}],
            "views": {"resolution": [32, 32], "supersample": 1, "distances": [3],
                      "elevations": [20], "azimuths": 1},
            "forests": {"sizes": [1], "frames": 1, "warmup": 0, "blocks": 1}})",
        "fuzz assets config");
    config["methods"] = methods;
    RunOptions options;
    options.outDirectory = run;
    options.saveImages = false;
    options.printTable = false;
    const ExperimentConfig experiment = parseExperimentConfig(config, "");
    runExperiment(experiment, options);
    const fs::path treeFolder = run / "assets" / safeName("sparse_s2_l100");
    for (const MethodVariant& variant : experiment.variants) {
      result.methods.push_back(variant.method);
      result.params.push_back(variant.params);
      result.folders.push_back(treeFolder / safeName(variant.label));
      std::vector<fs::path> files;
      for (const auto& entry : fs::directory_iterator(result.folders.back()))
        if (entry.is_regular_file()) files.push_back(entry.path());
      std::sort(files.begin(), files.end());
      result.files.push_back(files);
    }
    return result;
  }();
  return assets;
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

void runAssetLoader(const uint8_t* data, size_t size) {
  quietLogs();
  const BakedAssets& assets = bakedAssets();
  if (size < 2) return;
  const size_t m = data[0] % assets.methods.size();
  const std::vector<fs::path>& files = assets.files[m];
  if (files.empty()) return;
  const fs::path& file = files[data[1] % files.size()];
  const std::string original = readAll(file);
  writeBytes(file, data + 2, size - 2);
  expectNoBug([&] {
    auto method = builtinMethods().find(assets.methods[m]).create(assets.params[m], "fuzz");
    AssetFolder folder(assets.folders[m]);
    method->load(folder);
  });
  writeText(file, original);
}

const std::vector<Target>& targets() {
  static const std::vector<Target> all = {{"config", runConfig},
                                          {"tree_loader", runTreeLoader},
                                          {"captures", runCaptures},
                                          {"camera_path", runCameraPath},
                                          {"asset_loader", runAssetLoader}};
  return all;
}

}  // namespace canopy::fuzz
