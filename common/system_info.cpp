#include "common/system_info.h"

#include <array>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <string>

namespace canopy {

#ifndef CANOPY_SOURCE_DIR
#define CANOPY_SOURCE_DIR "."
#endif

uint64_t peakRssBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  }
  return 0;
}

bool resetPeakRss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

std::string cpuModel() {
  std::ifstream info("/proc/cpuinfo");
  std::string line;
  while (std::getline(info, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  }
  return "unknown";
}

namespace {
std::string runCommand(const std::string& command) {
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(::popen(command.c_str(), "r"), ::pclose);
  if (!pipe) return "";
  std::string output;
  std::array<char, 256> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe.get())) output += buffer.data();
  while (!output.empty() && (output.back() == '\n' || output.back() == '\r')) output.pop_back();
  return output;
}
}  // namespace

namespace {
// What decides the numbers a run prints: the code and its build. Results, figures and docs may
// change without making a run of the same config stale.
constexpr const char* kCodePaths =
    "common methods bench viewer cmake CMakeLists.txt CMakePresets.json";

std::string gitIn(const std::string& arguments) {
  return runCommand("git -C '" + std::string(CANOPY_SOURCE_DIR) + "' " + arguments +
                    " 2>/dev/null");
}
}  // namespace

std::string gitCommit() {
  const std::string commit = gitIn("rev-parse HEAD");
  if (commit.empty()) return "unknown";
  const std::string dirty =
      gitIn(std::string("status --porcelain --untracked-files=no -- ") + kCodePaths);
  return dirty.empty() ? commit : commit + "+dirty";
}

std::string codeVersion() {
  const std::string commit = gitCommit();
  if (commit == "unknown" || !commit.ends_with("+dirty")) return commit;
  // The uncommitted change itself, hashed (FNV-1a 64), so two different edits are two versions.
  const std::string diff = gitIn(std::string("diff HEAD -- ") + kCodePaths);
  uint64_t hash = 14695981039346656037ULL;
  for (unsigned char c : diff) {
    hash ^= c;
    hash *= 1099511628211ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return commit + "." + hex;
}

std::string isoTimestampUtc() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

}  // namespace canopy
