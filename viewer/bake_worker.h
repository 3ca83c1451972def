#pragma once

#include <chrono>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <string>

#include "common/image.h"
#include "common/tree.h"
#include "methods/method.h"

namespace canopy {

// Bakes a method on a worker thread, so the window stays live. The GL work a bake needs
// (photographs of the reference, for image-based methods) is queued to the GL thread, which
// serves it every frame from poll().
class BakeWorker {
 public:
  using Photographer = std::function<ImageRgbaF(const Camera&, int, int)>;

  ~BakeWorker() { wait(); }

  bool busy() const { return mBake.valid(); }
  // Starts baking `method` of `tree` (which must outlive the bake); `photograph` runs on the GL
  // thread.
  void start(std::unique_ptr<Method> method, const Tree& tree, std::string label,
             const Photographer& photograph);
  // On the GL thread, once a frame: serves queued GL work; returns the method once baked (and
  // rethrows what the bake threw), else null.
  std::unique_ptr<Method> poll();
  void wait();

  const std::string& label() const { return mLabel; }
  double elapsedSeconds() const;  // of the bake under way
  double lastBakeSeconds() const { return mLastSeconds; }

 private:
  // Work for the GL thread: a photograph, made when the GL thread serves the queue.
  ImageRgbaF runOnGlThread(std::function<ImageRgbaF()> work);
  void serve();

  std::mutex mMutex;
  std::deque<std::packaged_task<ImageRgbaF()>> mTasks;
  std::future<std::unique_ptr<Method>> mBake;
  std::chrono::steady_clock::time_point mStarted;
  std::string mLabel;
  double mLastSeconds = 0.0;
};

}  // namespace canopy
