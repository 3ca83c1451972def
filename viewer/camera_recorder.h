#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/views.h"
#include "viewer/camera_controller.h"

namespace canopy {

// The viewer's camera memory: bookmarks (B; CameraController states in a JSON file) and camera
// paths recorded frame by frame (R) in the format canopy-bench replays (common/camera_path.h).
// Each action returns the status line the UI shows.
class CameraRecorder {
 public:
  CameraRecorder(std::string bookmarksFile, std::string pathFile)
      : mBookmarksFile(std::move(bookmarksFile)), mPathFile(std::move(pathFile)) {}

  // Reads the bookmarks file if there is one; InputError naming it when it is malformed.
  void loadBookmarks();
  std::string addBookmark(const CameraController& camera);
  size_t bookmarkCount() const { return mBookmarks.size(); }
  // Puts bookmark i into `camera`; false when the bookmark is malformed.
  bool goTo(size_t i, CameraController& camera) const;

  bool recording() const { return mRecording; }
  // Starts, or stops and writes, the recording.
  std::string toggleRecording(const std::string& treeLabel);
  void record(const Camera& camera) {
    if (mRecording) mPath.push_back(camera);
  }

 private:
  std::string mBookmarksFile, mPathFile;
  std::vector<nlohmann::json> mBookmarks;
  bool mRecording = false;
  std::vector<Camera> mPath;
};

}  // namespace canopy
