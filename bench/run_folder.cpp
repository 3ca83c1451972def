#include "bench/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench/run_meta.h"
#include "common/error.h"

namespace canopy {
namespace {

// meta.json of an earlier run, or nothing when there is none or it cannot be read (then the
// run is no run of this config and code).
std::optional<RunMeta> readMeta(const std::filesystem::path& directory) {
  try {
    return readRunMeta(directory);
  } catch (const InputError&) {
    return std::nullopt;
  }
}

bool holdsRecords(const std::filesystem::path& directory) {
  std::error_code error;
  const auto metrics = directory / "metrics.jsonl";
  return std::filesystem::is_regular_file(metrics, error) &&
         std::filesystem::file_size(metrics, error) > 0;
}

std::string utcStamp() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y%m%dT%H%M%SZ", &utc);
  return buffer;
}

std::string orUnknown(const Absent<std::string>& value) {
  return value ? *value : std::string("unknown");
}

}  // namespace

RunFolder::RunFolder(std::filesystem::path directory, const RunIdentity& identity,
                     ResumePolicy policy)
    : mDirectory(std::move(directory)) {
  lock();
  if (!holdsRecords(mDirectory)) return;
  const std::optional<RunMeta> meta = readMeta(mDirectory);
  const std::string hash = meta ? orUnknown(meta->configHash) : "unknown";
  const std::string code = meta ? orUnknown(meta->codeVersion) : "unknown";
  const bool same = hash == identity.configHash && code == identity.codeVersion;
  const bool finished = meta && meta->finished;
  bool resume = false;
  switch (policy) {
    case ResumePolicy::kResume:
      resume = same;  // a finished run too: nothing is redone, the summaries are rewritten
      break;
    case ResumePolicy::kFresh:
      break;
    case ResumePolicy::kResumeOrFresh:
      resume = same && !finished;
      break;
  }
  if (resume) {
    if (meta && meta->runs) mEarlierRuns = *meta->runs;
    // An interrupted run's records stay; its start is kept so the folder says it ran in parts.
    if (meta && !finished) {
      mEarlierRuns.push_back({{"started", meta->started ? *meta->started : "unknown"},
                              {"finished", nullptr},
                              {"interrupted", true},
                              {"code_version", code},
                              {"gl_renderer", meta->gl.renderer},
                              {"shard", meta->shard ? *meta->shard : "0/1"}});
    }
    return;
  }
  if (policy == ResumePolicy::kResume) {
    throwInputError(
        "{}: holds a run of {} (config {}, code {}), not of this config ({}) and code ({}); pass "
        "--fresh to move it aside and start anew",
        mDirectory.string(), meta ? meta->experiment : "unknown", hash, code, identity.configHash,
        identity.codeVersion);
  }
  // Move the earlier run aside, then hold the new, empty folder.
  std::filesystem::path aside = mDirectory;
  aside += ".previous-" + utcStamp();
  for (int n = 2; std::filesystem::exists(aside); ++n) {
    aside = mDirectory;
    aside += fmt::format(".previous-{}-{}", utcStamp(), n);
  }
  std::error_code error;
  std::filesystem::rename(mDirectory, aside, error);
  if (error)
    throwInputError("{}: cannot move the earlier run aside ({})", mDirectory.string(),
                    error.message());
  ::close(mLockFd);  // the lock moved with the folder; take the new folder's
  mLockFd = -1;
  lock();
  mMovedAside = aside;
  spdlog::info("{}: the earlier run ({}, finished: {}) moved to {}", mDirectory.string(),
               same ? "same config and code" : "another config or code", finished ? "yes" : "no",
               aside.string());
}

RunFolder::~RunFolder() {
  if (mLockFd >= 0) ::close(mLockFd);  // releases the flock
}

void RunFolder::lock() {
  std::error_code error;
  std::filesystem::create_directories(mDirectory, error);
  if (error || !std::filesystem::is_directory(mDirectory)) {
    throwInputError("{}: cannot create the output folder ({})", mDirectory.string(),
                    error ? error.message() : "not a directory");
  }
  const auto path = mDirectory / ".lock";
  mLockFd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (mLockFd < 0) {
    throwInputError("{}: cannot open the lock file ({})", path.string(), std::strerror(errno));
  }
  if (::flock(mLockFd, LOCK_EX | LOCK_NB) != 0) {
    char owner[32] = {0};
    const ssize_t n = ::pread(mLockFd, owner, sizeof owner - 1, 0);
    ::close(mLockFd);
    mLockFd = -1;
    throwInputError("{}: another canopy-bench run (pid {}) is writing into this folder",
                    mDirectory.string(), n > 0 ? std::string(owner, size_t(n)) : "unknown");
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(mLockFd, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(mLockFd, pid.data(), pid.size(), 0);
  }
}

}  // namespace canopy
