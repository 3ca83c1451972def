// The NeRF-layout capture reader: camera convention, round trip with the writer, and every bad
// input naming its file.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "common/captures.h"
#include "test_support.h"

namespace canopy {
namespace {

// A view of a small opaque square in the middle of the image, so the hull is not empty.
CapturedView squareView(const Camera& camera, int size) {
  CapturedView view{camera, ImageRgbaF(size, size), ""};
  for (int y = size / 3; y < 2 * size / 3; ++y)
    for (int x = size / 3; x < 2 * size / 3; ++x) {
      float* p = view.image.at(x, y);
      p[0] = 0.2f, p[1] = 0.5f, p[2] = 0.1f, p[3] = 1.0f;
    }
  return view;
}

// Views on two rings (20° and 60° elevation), as a capture around an object is taken.
std::vector<CapturedView> ring(int count, int size) {
  Aabb bounds;
  bounds.min = glm::vec3(-1.0f);
  bounds.max = glm::vec3(1.0f);
  std::vector<CapturedView> views;
  for (int i = 0; i < count; ++i) {
    const float elevation = i % 2 ? 60.0f : 20.0f;
    views.push_back(
        squareView(orbitCamera(bounds, {4.0f, elevation, 360.0f * i / count}, 40.0f), size));
  }
  return views;
}

TEST(NerfCaptures, TransformMatrixIsCameraToWorldLookingDownMinusZ) {
  glm::mat4 cameraToWorld(1.0f);
  cameraToWorld[3] = glm::vec4(0, 0, 4, 1);
  const Camera camera = cameraFromNerf(cameraToWorld, glm::radians(90.0f), 64, 32);
  EXPECT_NEAR(glm::length(camera.position - glm::vec3(0, 0, 4)), 0.0f, 1e-6f);
  const glm::vec3 forward = glm::normalize(camera.target - camera.position);
  EXPECT_NEAR(glm::length(forward - glm::vec3(0, 0, -1)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(camera.up - glm::vec3(0, 1, 0)), 0.0f, 1e-6f);
  // tan(fovY/2) = tan(fovX/2) · h / w = 0.5.
  EXPECT_NEAR(camera.fovYDegrees, glm::degrees(2.0f * std::atan(0.5f)), 1e-4f);
  // A Z-up capture's camera tilted to look along +Y: columns are the camera axes in world space.
  glm::mat4 tilted(1.0f);
  tilted[1] = glm::vec4(0, 0, 1, 0);   // camera up = world +Z
  tilted[2] = glm::vec4(0, -1, 0, 0);  // camera back = world −Y, so it looks along +Y
  const Camera zUp = cameraFromNerf(tilted, 1.0f, 32, 32);
  EXPECT_NEAR(glm::length(glm::normalize(zUp.target - zUp.position) - glm::vec3(0, 1, 0)), 0.0f,
              1e-6f);
}

TEST(NerfCaptures, WrittenFolderReadsBackWithTheSameCamerasAndImages) {
  test::TempDir dir;
  const auto train = ring(8, 48), test = ring(3, 48);
  writeNerfCaptures(dir.path(), train, test);
  const CaptureSet set = readNerfCaptures(dir.path());
  ASSERT_EQ(set.train.size(), 8u);
  ASSERT_EQ(set.test.size(), 3u);
  for (size_t i = 0; i < train.size(); ++i) {
    const Camera& a = train[i].camera;
    const Camera& b = set.train[i].camera;
    EXPECT_LT(glm::length(a.position - b.position), 1e-4f);
    EXPECT_LT(
        glm::length(glm::normalize(a.target - a.position) - glm::normalize(b.target - b.position)),
        1e-5f);
    EXPECT_NEAR(a.fovYDegrees, b.fovYDegrees, 1e-3f);
    const float* p = set.train[i].image.at(24, 24);
    EXPECT_NEAR(p[3], 1.0f, 1e-6f);
    EXPECT_NEAR(p[1], 0.5f, 0.01f);  // through 8-bit sRGB and back
    EXPECT_EQ(set.train[i].image.at(2, 2)[3], 0.0f);
  }
  // The visual hull of the square's views is a small box around the origin.
  ASSERT_FALSE(set.bounds.empty());
  EXPECT_TRUE(set.bounds.contains(glm::vec3(0.0f)));
  EXPECT_LT(glm::length(set.bounds.extent()), 4.0f);
}

void expectErrorNaming(const std::filesystem::path& folder, const std::string& needle) {
  try {
    readNerfCaptures(folder);
    ADD_FAILURE() << "accepted; expected an error naming " << needle;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(needle), std::string::npos) << error.what();
  }
}

TEST(NerfCaptures, BadInputIsAnErrorNamingTheFile) {
  test::TempDir dir;
  expectErrorNaming(dir / "nowhere", "nowhere");
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  // Malformed JSON.
  test::writeText(dir / "transforms_test.json", "{\"camera_angle_x\": 0.7, \"frames\": [");
  expectErrorNaming(dir.path(), "transforms_test.json");
  // Missing key.
  test::writeText(dir / "transforms_test.json", R"({"frames": []})");
  expectErrorNaming(dir.path(), "transforms_test.json");
  // Missing image.
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  std::filesystem::remove(dir / "test" / "r_1.png");
  expectErrorNaming(dir.path(), "r_1.png");
  // An image of another size.
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 40));
  expectErrorNaming(dir.path(), "r_0.png");
  // A matrix that is not 4×4.
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  test::writeText(dir / "transforms_train.json",
                  R"({"camera_angle_x": 0.7, "frames": [{"file_path": "./train/r_0",
                      "transform_matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}]})");
  expectErrorNaming(dir.path(), "transforms_train.json");
  // Missing transforms file.
  std::filesystem::remove(dir / "transforms_train.json");
  expectErrorNaming(dir.path(), "transforms_train.json");
}

// A frame whose matrix is 4×4 and finite but no camera pose.
void expectMatrixRejected(const std::string& matrix, const std::string& words) {
  test::TempDir dir;
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  test::writeText(dir / "transforms_train.json",
                  R"({"camera_angle_x": 0.7, "frames": [{"file_path": "./train/r_0",
                      "transform_matrix": )" +
                      matrix + "}]}");
  expectErrorNaming(dir.path(), "transforms_train.json: frames[0]");
  expectErrorNaming(dir.path(), words);
}

TEST(NerfCaptures, MatricesThatAreNoCameraPoseAreRejected) {
  // Rank 2: the backward axis is the right axis again.
  expectMatrixRejected("[[1, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 4], [0, 0, 0, 1]]", "rank");
  // All zero rotation.
  expectMatrixRejected("[[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 4], [0, 0, 0, 1]]", "rank");
  // A projective last row.
  expectMatrixRejected("[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 1, 1]]", "last row");
  // Strings where numbers belong.
  expectMatrixRejected(R"([["1", 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]])", "4×4");
}

TEST(NerfCaptures, ImagesWithoutAlphaAreRejectedNotTakenAsOpaque) {
  test::TempDir dir;
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  // Overwrite one image with an RGB PNG of the same size: no coverage information.
  auto output = OIIO::ImageOutput::create("png");
  ASSERT_TRUE(output);
  const std::vector<uint8_t> rgb(32 * 32 * 3, 128);
  const std::string path = (dir / "test" / "r_1.png").string();
  ASSERT_TRUE(output->open(path, OIIO::ImageSpec(32, 32, 3, OIIO::TypeDesc::UINT8)));
  ASSERT_TRUE(output->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
  ASSERT_TRUE(output->close());
  expectErrorNaming(dir.path(), "r_1.png: no alpha channel");
}

TEST(NerfCaptures, DuplicateKeysAreRejected) {
  test::TempDir dir;
  writeNerfCaptures(dir.path(), ring(4, 32), ring(2, 32));
  test::writeText(dir / "transforms_test.json",
                  R"({"camera_angle_x": 0.7, "camera_angle_x": 0.2, "frames": []})");
  expectErrorNaming(dir.path(), "appears twice");
}

}  // namespace
}  // namespace canopy
