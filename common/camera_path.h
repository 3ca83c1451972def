#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "common/views.h"

namespace canopy {

// A camera path as canopy-view records it (key R) and canopy-bench replays it
// ("forests": {"camera_path": FILE}): {"tree": label, "units": ..., "frames": [{"position",
// "target", "up", "fov_deg"}, ...]}, in world units of the tree at the origin. One reader and one
// writer, so the two programs cannot disagree on the format.
struct CameraPathFile {
  std::string tree;  // the tree it was recorded around (informative)
  std::vector<Camera> frames;
};

// Writes the path atomically.
void writeCameraPath(const std::filesystem::path& path, const CameraPathFile& file);

// Reads and checks a path: at least one frame, finite positions, a field of view in (1°, 170°),
// a target apart from the position and an up vector not parallel to the view direction; each
// error is an InputError naming the file and the frame. Near and far planes are set for a forest
// seen from the path (0.05 and 5000 world units).
std::vector<Camera> readCameraPath(const std::filesystem::path& path);

}  // namespace canopy
