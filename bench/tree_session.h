#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/experiment.h"
#include "bench/harness.h"
#include "bench/records.h"
#include "bench/run_names.h"
#include "common/tree.h"
#include "methods/method.h"

namespace canopy {

class ResultsStore;

// A view every method of a tree is scored on: an orbit or close-up pose around a mesh tree, or a
// held-out test view of a capture (whose reference is the photograph itself).
struct EvalView {
  std::string key;  // unique per tree: names its record and image file
  Camera camera;
  int width = 0, height = 0;
  std::string ring;                      // "orbit", "closeup" or "capture"
  double distance = 0.0;                 // bounding radii (rounded to 0.1 for capture views)
  Absent<double> elevation, azimuth;     // orbit and close-up poses
  Absent<std::string> captureView;       // a capture view's photograph
  const ImageRgbaF* captured = nullptr;  // the reference of a capture view
};

// The views of a tree: the orbit rings and the close-up ring of the config, or a capture's test
// views.
std::vector<EvalView> evaluationViews(const Tree& tree, const ViewSettings& views);

// A method baked and uploaded under its own ledger owner, with its kind:"bake" record (tree,
// variant and renderer for the runner to fill).
struct BakedMethod {
  std::unique_ptr<Method> method;
  BakeRecord record;
};

// Everything the run needs of one tree, owned in one place: the tree, its views, and the
// polygonal reference with the images and frames made from it, each made on first need.
class TreeSession {
 public:
  TreeSession(Tree tree, std::string label, const ExperimentConfig& config, gl::Device& device,
              Harness& harness);

  const Tree& tree() const { return mTree; }
  const std::string& label() const { return mLabel; }
  const std::vector<EvalView>& views() const { return mViews; }
  bool hasMesh() const { return !mTree.captures; }

  // The reference, baked once (null for capture trees, which have no mesh to draw).
  Method* reference();
  // The reference image of a view, composited (the photograph itself for a capture view) and
  // prepared for FLIP once for every method scored on it; written under
  // images/<tree>/reference/ when an image folder is set.
  const FlipReference& scoredReference(const EvalView& view);
  const ImageRgba8& referenceImage(const EvalView& view) { return scoredReference(view).image(); }
  void setImageFolder(std::filesystem::path folder) { mImageFolder = std::move(folder); }
  // How image-based methods photograph a mesh tree: through the reference, as a camera would.
  ImageRgbaF photograph(const Camera& camera, int width, int height);
  // The context a bake of this tree gets.
  BakeContext bakeContext();
  // The reference's frames along a popping path, rendered once per path name.
  const std::vector<ImageRgba8>& referencePath(const std::string& name,
                                               const std::vector<PathFrame>& path, int width,
                                               int height);
  // A forest of `size` trees of this one, laid out from the config's seed.
  std::vector<Instance> forest(int size) const;
  // The reference's scored frames of the forest of `size` trees (Harness::timeInterleaved fills
  // them on first use; the run's forest timing is the same for every method).
  ReferenceFrames& forestFrames(int size) { return mForestFrames[size]; }

 private:
  Tree mTree;
  std::string mLabel;
  const ExperimentConfig& mConfig;
  gl::Device& mDevice;
  Harness& mHarness;
  std::vector<EvalView> mViews;
  std::optional<BakedMethod> mReference;
  std::map<std::string, FlipReference> mReferenceImages;
  std::map<int, ReferenceFrames> mForestFrames;
  std::map<std::string, std::vector<ImageRgba8>> mReferencePaths;
  std::optional<std::filesystem::path> mImageFolder;
};

// Bakes and uploads a method variant under its own ledger owner and measures what its bake
// record needs (bake time and peak RSS, ledger memory, the saved asset's size when
// `assetFolder` is set).
BakedMethod bakeMethod(const MethodVariant& variant, const Tree& tree, gl::Device& device,
                       BakeContext context,
                       const std::optional<std::filesystem::path>& assetFolder);

}  // namespace canopy
