#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace canopy {

// A progress bar on stderr for every loop a user waits for. On a terminal it redraws one line;
// otherwise (CI logs) it prints a line at every 10 %. Disabled bars print nothing.
class ProgressBar {
 public:
  ProgressBar(std::string label, size_t total, bool enabled = true);
  ~ProgressBar();
  void advance(size_t steps = 1);
  void setLabel(std::string label);
  void finish();

  // Global switch (--quiet).
  static void setEnabled(bool enabled);
  static bool enabled();

 private:
  void draw(size_t done, bool force);

  std::string mLabel;
  size_t mTotal;
  bool mEnabled;
  bool mTerminal;
  bool mFinished = false;
  std::atomic<size_t> mDone{0};
  int mLastDecile = -1;
  std::chrono::steady_clock::time_point mStart;
  std::mutex mMutex;
};

}  // namespace canopy
