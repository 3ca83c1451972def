// canopy-view as a script runs it: under Xvfb with --screenshot, for every registered method, the
// image shows the tree where the camera frames it; bad input is one line and exit code 2.
#include <gtest/gtest.h>

#include "common/camera_path.h"
#include "common/image.h"
#include "methods/method.h"
#include "test_support.h"
#include "viewer/camera_controller.h"
#include "viewer/camera_recorder.h"

namespace canopy {
namespace {

const std::string kView = CANOPY_VIEW_EXE;

std::string quickParams(const std::string& method) {
  if (method == "volumetric_opacity")
    return R"( --params '{"views": 8, "capture_resolution": 96, "level": 3}')";
  return "";
}

class ViewerScreenshot : public testing::TestWithParam<std::string> {};

TEST_P(ViewerScreenshot, ShowsTheTreeInTheFramedRegion) {
  test::TempDir dir;
  const auto shot = dir / "shot.png";
  std::string error;
  const int code = test::runUnderXvfb(
      kView + " --tree sparse --leaves 500 --method " + GetParam() + quickParams(GetParam()) +
          " --width 320 --height 240 --frames 2 --hide-ui --screenshot " + shot.string() +
          " --bookmarks " + (dir / "b.json").string(),
      &error);
  ASSERT_EQ(code, 0) << error;
  const ImageRgba8 image = readImage(shot);
  ASSERT_EQ(image.width, 320);
  ASSERT_EQ(image.height, 240);
  // 500 leaves: more than the largest default K (multi-layer's 400 clusters).
  // The tree is what differs from the background (sRGB 0.5, 0.6, 0.75); the orbit camera frames
  // it from 3 radii, so it covers a good share of the image and stays inside the middle.
  long tree = 0, outside = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.at(x, y);
      const bool background =
          std::abs(p[0] - 128) <= 3 && std::abs(p[1] - 153) <= 3 && std::abs(p[2] - 191) <= 3;
      if (background) continue;
      ++tree;
      const bool middle = x > image.width / 6 && x < image.width * 5 / 6 && y > 0;
      outside += middle ? 0 : 1;
    }
  }
  EXPECT_GT(tree, image.width * image.height / 50) << "the tree is visible";
  EXPECT_LT(outside, tree / 20 + 1) << "and where the camera frames it";
}

INSTANTIATE_TEST_SUITE_P(EveryRegisteredMethod, ViewerScreenshot,
                         testing::ValuesIn(builtinMethods().names()),
                         [](const testing::TestParamInfo<std::string>& info) {
                           return info.param;
                         });

TEST(Viewer, LitShadowedScreenshotIsTheTreeAndDarkerThanUnlit) {
  test::TempDir dir;
  for (const char* mode : {"", " --shadows"}) {
    const auto shot = dir / (std::string(mode).empty() ? "unlit.png" : "shadows.png");
    std::string error;
    ASSERT_EQ(test::runUnderXvfb(kView +
                                     " --tree sparse --leaves 500 --method multilayer_indirect"
                                     " --width 240 --height 200 --frames 2 --hide-ui" +
                                     mode + " --screenshot " + shot.string(),
                                 &error),
              0)
        << error;
  }
  const ImageRgba8 unlit = readImage(dir / "unlit.png"), shadowed = readImage(dir / "shadows.png");
  long darker = 0, same = 0;
  for (size_t i = 0; i < unlit.pixels.size(); i += 4) {
    const bool background = unlit.pixels[i] == 128 && unlit.pixels[i + 1] == 153;
    if (background) continue;
    (shadowed.pixels[i + 1] + 2 < unlit.pixels[i + 1] ? darker : same) += 1;
  }
  EXPECT_GT(darker, 100) << "lighting and shadows change the leaves";
}

int errorLines(const std::string& text) {
  return int(std::count(text.begin(), text.end(), '\n'));
}

TEST(Viewer, BadInputIsOneLineAndExitCode2) {
  test::TempDir dir;
  std::string error;
  // No display.
  EXPECT_EQ(test::runCommand("env -u DISPLAY -u WAYLAND_DISPLAY " + kView +
                                 " --tree sparse --screenshot " + (dir / "x.png").string(),
                             &error),
            2);
  EXPECT_NE(error.find("display"), std::string::npos) << error;
  EXPECT_EQ(errorLines(error), 1) << error;
  // Unknown method, missing tree file, bad parameters: before any window opens.
  EXPECT_EQ(test::runCommand(kView + " --method no_such_method", &error), 2);
  EXPECT_NE(error.find("no_such_method"), std::string::npos) << error;
  EXPECT_EQ(errorLines(error), 1) << error;
  EXPECT_EQ(test::runCommand(kView + " --tree /nowhere/tree.obj", &error), 2);
  EXPECT_NE(error.find("/nowhere/tree.obj"), std::string::npos) << error;
  EXPECT_EQ(
      test::runCommand(kView + " --method bbox_hierarchy --params '{\"texture_size\": 0}'", &error),
      2);
  EXPECT_NE(error.find("texture_size"), std::string::npos) << error;
  // Out-of-range and malformed options, hostile --params: one line, exit 2, no window needed.
  for (const auto& [options, words] : std::vector<std::pair<std::string, std::string>>{
           {"--leaves -1", "--leaves"},
           {"--leaves 4294967297", "--leaves"},
           {"--frobnicate", "--frobnicate"},
           {R"(--params '{"a": 1, "a": 2}')", "appears twice"},
           {"--params '" + std::string(100, '[') + "'", "--params"},
           {"--width 1e400", "--width"}}) {
    EXPECT_EQ(test::runCommand(kView + " " + options, &error), 2) << options << ": " << error;
    EXPECT_NE(error.find(words), std::string::npos) << options << ": " << error;
    EXPECT_EQ(errorLines(error), 1) << options << ": " << error;
  }
  // A screenshot into a folder that does not exist names the folder.
  EXPECT_EQ(
      test::runUnderXvfb(kView + " --tree sparse --leaves 200 --hide-ui --frames 1 --screenshot " +
                             (dir / "missing" / "x.png").string() + " --bookmarks " +
                             (dir / "b.json").string(),
                         &error),
      2);
  EXPECT_NE(error.find((dir / "missing").string()), std::string::npos) << error;
}

// The viewer's recorder writes the camera-path format the bench replays (one reader, one writer).
TEST(CameraRecorder, RecordedPathsAreWhatTheBenchReplays) {
  test::TempDir dir;
  CameraRecorder recorder((dir / "b.json").string(), (dir / "path.json").string());
  CameraController controller;
  controller.frameTree(test::smallTree(50).bounds);
  EXPECT_EQ(recorder.toggleRecording("sparse"), "recording the camera path");
  const Camera first = controller.camera(40.0f);
  recorder.record(first);
  controller.update({30.0f, 0.0f}, 0.0f, glm::vec3(0.0f), 0.1f);
  const Camera second = controller.camera(35.0f);
  recorder.record(second);
  EXPECT_NE(recorder.toggleRecording("sparse").find("2 frames"), std::string::npos);
  const std::vector<Camera> path = readCameraPath(dir / "path.json");
  ASSERT_EQ(path.size(), 2u);
  EXPECT_EQ(path[0].position, first.position);
  EXPECT_EQ(path[1].target, second.target);
  EXPECT_FLOAT_EQ(path[1].fovYDegrees, 35.0f);
  EXPECT_NE(path[0].position, path[1].position) << "the camera moved between the frames";
  EXPECT_NE(recorder.addBookmark(controller).find("bookmark 1"), std::string::npos);
  CameraRecorder again((dir / "b.json").string(), (dir / "path2.json").string());
  again.loadBookmarks();
  EXPECT_EQ(again.bookmarkCount(), 1u);
}

}  // namespace
}  // namespace canopy
