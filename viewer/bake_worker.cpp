#include "viewer/bake_worker.h"

namespace canopy {

void BakeWorker::start(std::unique_ptr<Method> method, const Tree& tree, std::string label,
                       const Photographer& photograph) {
  mStarted = std::chrono::steady_clock::now();
  mLabel = std::move(label);
  mBake =
      std::async(std::launch::async, [this, &tree, m = std::move(method), photograph]() mutable {
        BakeContext context;
        context.photograph = [this, photograph](const Camera& camera, int width, int height) {
          return runOnGlThread([=] { return photograph(camera, width, height); });
        };
        m->bake(tree, context);
        return std::move(m);
      });
}

std::unique_ptr<Method> BakeWorker::poll() {
  serve();
  if (!mBake.valid() || mBake.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
    return nullptr;
  mLastSeconds = elapsedSeconds();
  return mBake.get();  // rethrows the bake's exception
}

void BakeWorker::wait() {
  // A bake waiting for a photograph needs the queue served to finish.
  while (mBake.valid() && mBake.wait_for(std::chrono::milliseconds(5)) != std::future_status::ready)
    serve();
  if (mBake.valid()) mBake.wait();
}

double BakeWorker::elapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - mStarted).count();
}

ImageRgbaF BakeWorker::runOnGlThread(std::function<ImageRgbaF()> work) {
  std::packaged_task<ImageRgbaF()> task(std::move(work));
  auto result = task.get_future();
  {
    std::lock_guard lock(mMutex);
    mTasks.push_back(std::move(task));
  }
  return result.get();
}

void BakeWorker::serve() {
  std::deque<std::packaged_task<ImageRgbaF()>> tasks;
  {
    std::lock_guard lock(mMutex);
    tasks.swap(mTasks);
  }
  for (auto& task : tasks) task();
}

}  // namespace canopy
