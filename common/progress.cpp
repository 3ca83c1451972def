#include "common/progress.h"

#include <unistd.h>

#include <cstdio>

#include <fmt/format.h>

namespace canopy {
namespace {
std::atomic<bool> gEnabled{true};
}

void ProgressBar::setEnabled(bool enabled) {
  gEnabled = enabled;
}
bool ProgressBar::enabled() {
  return gEnabled;
}

ProgressBar::ProgressBar(std::string label, size_t total, bool enabled)
    : mLabel(std::move(label)),
      mTotal(total),
      mEnabled(enabled && gEnabled && total > 0),
      mTerminal(::isatty(STDERR_FILENO) != 0),
      mStart(std::chrono::steady_clock::now()) {
  draw(0, true);
}

ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::setLabel(std::string label) {
  std::lock_guard lock(mMutex);
  mLabel = std::move(label);
}

void ProgressBar::advance(size_t steps) {
  draw(mDone += steps, false);
}

void ProgressBar::finish() {
  if (mFinished) return;
  mFinished = true;
  if (!mEnabled) return;
  draw(mDone.load(), true);
  if (mTerminal) std::fputc('\n', stderr);
}

void ProgressBar::draw(size_t done, bool force) {
  if (!mEnabled) return;
  std::lock_guard lock(mMutex);
  const double fraction = mTotal ? std::min(1.0, double(done) / double(mTotal)) : 1.0;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
  if (mTerminal) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::fprintf(stderr, "\r%s [%s%s] %zu/%zu %.0fs ", mLabel.c_str(),
                 std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(), done,
                 mTotal, seconds);
  } else {
    const int decile = static_cast<int>(fraction * 10.0);
    if (decile == mLastDecile && !force) return;
    if (decile == mLastDecile) return;
    mLastDecile = decile;
    std::fprintf(stderr, "%s: %zu/%zu (%.0f%%, %.1fs)\n", mLabel.c_str(), done, mTotal,
                 fraction * 100.0, seconds);
  }
  std::fflush(stderr);
}

}  // namespace canopy
