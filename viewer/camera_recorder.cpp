#include "viewer/camera_recorder.h"

#include <filesystem>

#include <fmt/format.h>

#include "common/atomic_file.h"
#include "common/camera_path.h"
#include "common/config.h"
#include "common/error.h"

namespace canopy {

void CameraRecorder::loadBookmarks() {
  if (!std::filesystem::exists(mBookmarksFile)) return;
  try {
    mBookmarks = readJsonFile(mBookmarksFile).at("bookmarks").get<std::vector<nlohmann::json>>();
  } catch (const nlohmann::json::exception& e) {
    throwInputError("{}: not a bookmarks file ({})", mBookmarksFile, e.what());
  }
}

std::string CameraRecorder::addBookmark(const CameraController& camera) {
  mBookmarks.push_back(camera.toJson());
  writeTextAtomically(mBookmarksFile, nlohmann::json({{"bookmarks", mBookmarks}}).dump(2));
  return fmt::format("bookmark {} saved to {}", mBookmarks.size(), mBookmarksFile);
}

bool CameraRecorder::goTo(size_t i, CameraController& camera) const {
  try {
    camera.fromJson(mBookmarks.at(i));
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

std::string CameraRecorder::toggleRecording(const std::string& treeLabel) {
  mRecording = !mRecording;
  if (mRecording) {
    mPath.clear();
    return "recording the camera path";
  }
  if (mPath.empty()) return "nothing recorded";
  writeCameraPath(mPathFile, {treeLabel, mPath});
  return fmt::format("{} frames saved to {}", mPath.size(), mPathFile);
}

}  // namespace canopy
