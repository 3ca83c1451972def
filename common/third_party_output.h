#pragma once

#include <cstdio>
#include <mutex>
#include <string>

namespace canopy {

// Holds what third-party libraries write to stderr on their own (libpng's "libpng error: …"
// lines, printed before OpenImageIO reports the same failure) while one call into them runs, so
// the message can be folded into Canopy's own one-line error instead of reaching the terminal.
// Redirects file descriptor 2 for its lifetime, one instance at a time process-wide (a mutex);
// keep the scope to the one library call, since other threads' output lands in it too.
class CapturedStderr {
 public:
  CapturedStderr();
  ~CapturedStderr();
  CapturedStderr(const CapturedStderr&) = delete;
  CapturedStderr& operator=(const CapturedStderr&) = delete;

  // Ends the capture (restores stderr) and returns what was written, as one line.
  std::string release();

 private:
  std::unique_lock<std::mutex> mLock;
  int mSavedDescriptor = -1;
  std::FILE* mCapture = nullptr;
  std::string mText;
  bool mReleased = false;
};

// Several lines of a library's message as one line: lines joined by "; ", empty and repeated
// lines dropped (OpenImageIO repeats libpng's line in its own words).
std::string asOneLine(const std::string& text);

}  // namespace canopy
