#include "common/third_party_output.h"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <set>
#include <sstream>

namespace canopy {

namespace {
std::mutex& captureMutex() {
  static std::mutex mutex;
  return mutex;
}
}  // namespace

CapturedStderr::CapturedStderr() : mLock(captureMutex()) {
  std::fflush(stderr);
  mCapture = std::tmpfile();
  mSavedDescriptor = mCapture ? ::dup(STDERR_FILENO) : -1;
  if (mSavedDescriptor < 0 || ::dup2(::fileno(mCapture), STDERR_FILENO) < 0) {
    // Without a temporary file the library's lines reach the terminal; nothing else changes.
    if (mSavedDescriptor >= 0) ::close(mSavedDescriptor);
    mSavedDescriptor = -1;
  }
}

CapturedStderr::~CapturedStderr() {
  release();
}

std::string CapturedStderr::release() {
  if (mReleased) return asOneLine(mText);
  mReleased = true;
  std::fflush(stderr);
  if (mSavedDescriptor >= 0) {
    ::dup2(mSavedDescriptor, STDERR_FILENO);
    ::close(mSavedDescriptor);
    std::rewind(mCapture);
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, mCapture)) > 0;)
      mText.append(buffer, n);
  }
  if (mCapture) std::fclose(mCapture);
  mLock.unlock();
  return asOneLine(mText);
}

std::string asOneLine(const std::string& text) {
  std::istringstream lines(text);
  std::set<std::string> seen;
  std::string line, out;
  while (std::getline(lines, line)) {
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) continue;
    line = line.substr(first);
    if (!seen.insert(line).second) continue;
    out += (out.empty() ? "" : "; ") + line;
  }
  return out;
}

}  // namespace canopy
