// The NeRF-layout capture reader: camera convention, round trip with the writer, intrinsics of
// nerfstudio and instant-ngp, and every bad input naming its file.
#include <functional>

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>

#include "common/capture_intrinsics.h"
#include "common/captures.h"
#include "common/error.h"
#include "common/image.h"
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

// Intrinsics as nerfstudio and instant-ngp write them: the frame's keys over the file's.
TEST(NerfCaptures, IntrinsicsAreReadFromTheFrameOverTheFile) {
  const nlohmann::json file = {{"fl_x", 100.0},
                               {"fl_y", 110.0},
                               {"cx", 30.0},
                               {"cy", 20.0},
                               {"w", 64},
                               {"h", 48},
                               {"camera_model", "OPENCV"},
                               {"k1", 0.0},
                               {"p1", 0.0}};
  PinholeIntrinsics k = readIntrinsics(file, nlohmann::json::object(), 64, 48, "f");
  EXPECT_EQ(k.focalX, 100.0);
  EXPECT_EQ(k.focalY, 110.0);
  EXPECT_EQ(k.centerX, 30.0);
  EXPECT_EQ(k.centerY, 20.0);
  EXPECT_FALSE(k.isCentredSquare());
  k = readIntrinsics(file, {{"cx", 33.5}, {"fl_y", 90.0}}, 64, 48, "f");
  EXPECT_EQ(k.centerX, 33.5);
  EXPECT_EQ(k.focalY, 90.0);
  EXPECT_EQ(k.centerY, 20.0);
  // Only angles: the principal point at the centre, square pixels unless camera_angle_y differs.
  k = readIntrinsics({{"camera_angle_x", glm::radians(90.0)}}, nlohmann::json::object(), 64, 48,
                     "f");
  EXPECT_NEAR(k.focalX, 32.0, 1e-9);
  EXPECT_EQ(k.focalY, k.focalX);
  EXPECT_TRUE(k.isCentredSquare());
  k = readIntrinsics(
      {{"camera_angle_x", glm::radians(90.0)}, {"camera_angle_y", glm::radians(90.0)}},
      nlohmann::json::object(), 64, 48, "f");
  EXPECT_NEAR(k.focalY, 24.0, 1e-9);
}

void expectIntrinsicsRejected(const nlohmann::json& file, const std::string& needle) {
  try {
    readIntrinsics(file, nlohmann::json::object(), 64, 48, "transforms_x.json: frames[2]");
    ADD_FAILURE() << file.dump() << " accepted; expected an error naming " << needle;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("transforms_x.json: frames[2]"), std::string::npos) << message;
    EXPECT_NE(message.find(needle), std::string::npos) << message;
  }
}

TEST(NerfCaptures, BadIntrinsicsAreErrorsNamingTheKey) {
  expectIntrinsicsRejected(nlohmann::json::object(), "fl_x or camera_angle_x");
  expectIntrinsicsRejected({{"fl_x", -5.0}}, "fl_x");
  expectIntrinsicsRejected({{"fl_x", "50"}}, "fl_x");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"fl_y", 0.0}}, "fl_y");
  expectIntrinsicsRejected({{"camera_angle_x", 4.0}}, "camera_angle_x");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"cx", 64.0}}, "cx");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"cy", -1.0}}, "cy");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"w", 640}}, "w = 640");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"h", 480}}, "h = 480");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"k1", 0.01}}, "k1");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"p2", -0.002}}, "p2");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"camera_model", "OPENCV_FISHEYE"}}, "camera_model");
  expectIntrinsicsRejected({{"fl_x", 50.0}, {"fl_y", 5000.0}}, "fl_y");
}

// A capture folder written by writeNerfCaptures, then every image rewritten through `edit` and
// its transforms files' camera_angle_x replaced by `intrinsics` (at the top level).
void rewriteCapture(const std::filesystem::path& folder,
                    const std::function<ImageRgba8(const ImageRgba8&)>& edit,
                    const nlohmann::json& intrinsics) {
  for (const char* split : {"train", "test"}) {
    const auto path = folder / (std::string("transforms_") + split + ".json");
    nlohmann::json json = nlohmann::json::parse(test::readText(path));
    json.erase("camera_angle_x");
    json.update(intrinsics);
    for (const auto& frame : json.at("frames")) {
      const auto image = folder / (frame.at("file_path").get<std::string>() + ".png");
      writePng(image, edit(readImage(image)));
    }
    test::writeText(path, json.dump());
  }
}

ImageRgba8 columns(const ImageRgba8& image, int from) {
  ImageRgba8 out(image.width - from, image.height);
  for (int y = 0; y < image.height; ++y)
    for (int x = from; x < image.width; ++x)
      std::copy_n(&image.pixels[(size_t(y) * image.width + x) * 4], 4,
                  &out.pixels[(size_t(y) * out.width + x - from) * 4]);
  return out;
}

// The same views written as a capture twice, the second rewritten (rewriteCapture), both read.
struct CapturePair {
  CaptureSet original, rewritten;
};
CapturePair readOriginalAndRewritten(const std::function<ImageRgba8(const ImageRgba8&)>& edit,
                                     const nlohmann::json& intrinsics) {
  test::TempDir whole, rewritten;
  const auto train = ring(6, 48), test = ring(2, 48);
  writeNerfCaptures(whole.path(), train, test);
  writeNerfCaptures(rewritten.path(), train, test);
  rewriteCapture(rewritten.path(), edit, intrinsics);
  return {readNerfCaptures(whole.path()), readNerfCaptures(rewritten.path())};
}

// The focal length in pixels of ring()'s views (40° vertical field of view, 48 pixels).
const double kRingFocal = 24.0 / std::tan(0.5 * glm::radians(40.0));

// Cropping an image moves its principal point: the cropped capture, read with its cx, gives the
// original camera and, where the crop kept pixels, the original image exactly.
TEST(NerfCaptures, AnOffCentrePrincipalPointIsResampledToTheCentredCamera) {
  const auto [a, b] = readOriginalAndRewritten(
      [](const ImageRgba8& image) { return columns(image, 8); }, {{"fl_x", kRingFocal},
                                                                  {"fl_y", kRingFocal},
                                                                  {"cx", 16.0},
                                                                  {"cy", 24.0},
                                                                  {"w", 40},
                                                                  {"h", 48}});
  ASSERT_EQ(b.train.size(), 6u);
  for (size_t i = 0; i < a.train.size(); ++i) {
    const ImageRgbaF& original = a.train[i].image;
    const ImageRgbaF& resampled = b.train[i].image;
    ASSERT_EQ(resampled.width, 48);
    ASSERT_EQ(resampled.height, 48);
    EXPECT_NEAR(b.train[i].camera.fovYDegrees, a.train[i].camera.fovYDegrees, 1e-3f);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 48; ++x) {
        for (int c = 0; c < 4; ++c) {
          const float expected = x >= 8 ? original.at(x, y)[c] : 0.0f;
          ASSERT_NEAR(resampled.at(x, y)[c], expected, 1e-6f) << x << "," << y;
        }
      }
    }
  }
}

// Pixels twice as wide as tall (every two columns averaged, fl_x halved): read back, the square's
// coverage is where the original's is, up to the blur of the lost columns.
TEST(NerfCaptures, NonSquarePixelsAreResampledToSquareOnes) {
  const auto squeeze = [](const ImageRgba8& image) {
    ImageRgba8 out(image.width / 2, image.height);
    for (size_t p = 0; p < out.pixels.size(); ++p) {
      const size_t x = p / 4 % size_t(out.width), y = p / 4 / size_t(out.width), c = p % 4;
      const size_t left = (y * size_t(image.width) + 2 * x) * 4 + c;
      out.pixels[p] = uint8_t((image.pixels[left] + image.pixels[left + 4] + 1) / 2);
    }
    return out;
  };
  const auto [a, b] = readOriginalAndRewritten(
      squeeze, {{"fl_x", kRingFocal / 2}, {"fl_y", kRingFocal}, {"cx", 12.0}, {"cy", 24.0}});
  for (size_t i = 0; i < a.train.size(); ++i) {
    ASSERT_EQ(b.train[i].image.width, 48);
    double difference = 0.0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 48; ++x)
        difference += std::abs(b.train[i].image.at(x, y)[3] - a.train[i].image.at(x, y)[3]);
    // Each of the square's 16 rows has four pixels at its vertical edges that bilinear
    // interpolation between a covered and an empty squeezed column leaves a quarter off.
    EXPECT_LT(difference, 16 * 4 * 0.25 + 0.5) << i;
    EXPECT_NEAR(b.train[i].image.at(24, 24)[3], 1.0f, 1e-6f);
  }
  EXPECT_TRUE(b.bounds.contains(glm::vec3(0.0f)));
}

}  // namespace
}  // namespace canopy
