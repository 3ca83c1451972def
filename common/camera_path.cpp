#include "common/camera_path.h"

#include <cmath>

#include <glm/geometric.hpp>

#include "common/atomic_file.h"
#include "common/config.h"
#include "common/json_fields.h"

namespace canopy {
namespace {

// One frame as stored: the fields of a Camera a path needs.
struct StoredFrame {
  glm::vec3 position{0.0f}, target{0.0f}, up{0.0f, 1.0f, 0.0f};
  float fovDegrees = 40.0f;
  template <class V>
  void visit(V& v) {
    v("position", position);
    v("target", target);
    v("up", up);
    v("fov_deg", fovDegrees);
  }
};

struct StoredPath {
  Absent<std::string> tree, units;
  std::vector<StoredFrame> frames;
  template <class V>
  void visit(V& v) {
    v("tree", tree);
    v("units", units);
    v("frames", frames);
  }
};

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

void writeCameraPath(const std::filesystem::path& path, const CameraPathFile& file) {
  StoredPath stored;
  stored.tree = file.tree;
  stored.units = std::string("world units of the tree at the origin");
  for (const Camera& c : file.frames)
    stored.frames.push_back({c.position, c.target, c.up, c.fovYDegrees});
  writeTextAtomically(path, writeFields(stored).dump(1));
}

std::vector<Camera> readCameraPath(const std::filesystem::path& path) {
  StoredPath stored;
  readFields(readJsonFile(path.string()), path.string(), stored);
  if (stored.frames.empty()) throwInputError("{}: a camera path needs frames", path.string());
  std::vector<Camera> cameras;
  for (const StoredFrame& f : stored.frames) {
    const size_t i = cameras.size();
    const glm::vec3 forward = f.target - f.position;
    if (!finite(f.position) || !finite(f.target) || !finite(f.up))
      throwInputError("{}: frame {} has a position, target or up that is not finite", path.string(),
                      i);
    if (!(f.fovDegrees > 1.0f && f.fovDegrees < 170.0f))
      throwInputError("{}: frame {}: fov_deg {} is outside (1, 170)", path.string(), i,
                      f.fovDegrees);
    if (glm::length(forward) < 1e-6f)
      throwInputError("{}: frame {}: the target is at the position", path.string(), i);
    if (glm::length(glm::cross(glm::normalize(forward), f.up)) < 1e-4f)
      throwInputError("{}: frame {}: the up vector is zero or along the view direction",
                      path.string(), i);
    Camera c;
    c.position = f.position;
    c.target = f.target;
    c.up = f.up;
    c.fovYDegrees = f.fovDegrees;
    // Near/far planes for a forest seen from the path.
    c.nearPlane = 0.05f;
    c.farPlane = 5000.0f;
    cameras.push_back(c);
  }
  return cameras;
}

}  // namespace canopy
