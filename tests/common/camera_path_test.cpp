// The camera-path format canopy-view writes and canopy-bench replays: one reader, one writer.
#include <gtest/gtest.h>

#include "common/camera_path.h"
#include "test_support.h"

namespace canopy {
namespace {

TEST(CameraPath, WhatTheViewerWritesTheBenchReads) {
  test::TempDir dir;
  Camera a, b;
  a.position = {1, 2, 3};
  a.target = {0, 1, 0};
  a.fovYDegrees = 35.0f;
  b.position = {-4, 2, 1};
  b.target = {0, 0.5f, 0};
  b.up = {0, 0, 1};
  writeCameraPath(dir / "path.json", {"oak", {a, b}});
  const std::vector<Camera> read = readCameraPath(dir / "path.json");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].position, a.position);
  EXPECT_EQ(read[0].target, a.target);
  EXPECT_FLOAT_EQ(read[0].fovYDegrees, 35.0f);
  EXPECT_EQ(read[1].up, b.up);
}

TEST(CameraPath, BadPathsNameTheFileAndTheFrame) {
  test::TempDir dir;
  const auto expectError = [&](const std::string& frames, const std::string& words) {
    test::writeText(dir / "p.json", R"({"frames": [)" + frames + "]}");
    try {
      readCameraPath(dir / "p.json");
      ADD_FAILURE() << frames << " was accepted";
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("p.json"), std::string::npos) << message;
      EXPECT_NE(message.find(words), std::string::npos) << message;
    }
  };
  const std::string good =
      R"({"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 1, 0], "fov_deg": 40})";
  expectError("", "needs frames");
  expectError(
      good + R"(, {"position": [0, 1, 5], "target": [0, 1, 5], "up": [0, 1, 0], "fov_deg": 40})",
      "frame 1");
  expectError(R"({"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 0, 1], "fov_deg": 40})",
              "up vector");
  expectError(R"({"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 1, 0], "fov_deg": 400})",
              "fov_deg");
  expectError(R"({"position": [0, 1], "target": [0, 1, 0], "up": [0, 1, 0], "fov_deg": 40})",
              "position");
  expectError(
      R"({"position": [0, 1, 5], "target": [0, 1, 0], "up": [0, 1, 0], "fov_deg": 40, "roll": 2})",
      "roll");
}

}  // namespace
}  // namespace canopy
