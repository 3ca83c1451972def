#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace canopy {

// What a run does with a folder that already holds records.
enum class ResumePolicy {
  kResume,         // (default) resume a run of the same config and code; refuse any other
  kFresh,          // --fresh: move any earlier run aside and start anew
  kResumeOrFresh,  // --resume-or-fresh (make bench): resume an unfinished run of the same config
                   // and code, otherwise move the earlier run aside and start anew
};

// The identity a resumed run must match: the config's hash and the code version
// (system_info.h codeVersion).
struct RunIdentity {
  std::string configHash;
  std::string codeVersion;
};

// An output folder held by this process. Construction creates the folder, takes an exclusive
// lock on DIR/.lock (a second process exits 2 naming the folder; the lock dies with the process,
// so a killed run never leaves it held) and applies the policy to what DIR holds: records of
// another config or code are refused (InputError suggesting --fresh) or moved aside to
// DIR.previous-<UTC time>, so a folder's records always come from one config and one code.
class RunFolder {
 public:
  RunFolder(std::filesystem::path directory, const RunIdentity& identity, ResumePolicy policy);
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  const std::filesystem::path& directory() const { return mDirectory; }
  // Where an earlier run was moved, if one was.
  const std::optional<std::filesystem::path>& movedAside() const { return mMovedAside; }
  // meta.json's "runs" of the run being resumed (empty for a new one), plus an entry with
  // "interrupted": true and "finished": null when the resumed run had not finished.
  const nlohmann::json& earlierRuns() const { return mEarlierRuns; }

 private:
  void lock();

  std::filesystem::path mDirectory;
  int mLockFd = -1;
  std::optional<std::filesystem::path> mMovedAside;
  nlohmann::json mEarlierRuns = nlohmann::json::array();
};

}  // namespace canopy
