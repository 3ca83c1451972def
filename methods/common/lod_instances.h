#pragma once

#include <functional>
#include <span>
#include <string>
#include <vector>

#include "common/gl/device.h"
#include "common/views.h"
#include "methods/method.h"

namespace canopy {

// A buffer of instance matrices rewritten every frame: it grows when a frame holds more than it
// can, and is charged to `owner` in the device's ledger.
class StreamedMatrices {
 public:
  void upload(gl::Device& device, const std::string& owner, std::span<const glm::mat4> matrices,
              const char* label);
  GLuint id() const { return mBuffer.id(); }

 private:
  gl::Buffer mBuffer;
  size_t mCapacity = 0;
};

// Sorts a frame's instances into levels of detail by their projected size in output pixels (the
// instance's bounding radius seen from the camera, FrameContext::projectedPixels) and uploads
// their matrices level by level into one buffer. Shared by the methods with geometric LoD.
class LodInstances {
 public:
  struct Range {
    GLint first = 0;
    GLsizei count = 0;
  };

  // The device and owner are remembered at upload, so the buffer is charged to the method.
  void attach(gl::Device& device, std::string owner);
  // `thresholds` decrease: an instance whose radius spans fewer than thresholds[i] pixels goes
  // past level i; level 0 holds the largest, the last level the rest. frame.forcedLevel >= 0 puts
  // every instance in that level.
  // `group` (optional) splits each level further: an instance's group in [0, groups) from its
  // level and model matrix; within a level the instances are ordered by group (nearest first
  // within a group, as given), and groupRanges(level) gives each group's part.
  using Grouping = std::function<int(int level, const glm::mat4& model)>;
  void update(const FrameContext& frame, std::span<const Instance> instances,
              const Aabb& treeBounds, const std::vector<float>& thresholds,
              const Grouping& group = {}, int groups = 1);
  GLuint buffer() const { return mBuffer.id(); }
  // A hash of every instance's level in the last update: changes when any instance switched.
  uint64_t signature() const { return mSignature; }
  const std::vector<Range>& ranges() const { return mRanges; }
  // Level `level`'s instances group by group (one range when update had no grouping).
  const std::vector<Range>& groupRanges(size_t level) const { return mGroupRanges[level]; }

  // The level an instance whose bounding radius spans `radiusPixels` output pixels gets.
  static int levelFor(float radiusPixels, const std::vector<float>& thresholds);

 private:
  gl::Device* mDevice = nullptr;
  std::string mOwner;
  StreamedMatrices mBuffer;
  std::vector<Range> mRanges;
  std::vector<std::vector<Range>> mGroupRanges;  // [level][group]
  std::vector<glm::mat4> mMatrices;
  uint64_t mSignature = 0;
};

// FNV-1a step over one 64-bit value: the LoD signatures' hash.
inline uint64_t fnv1aMix(uint64_t hash, uint64_t value) {
  for (int byte = 0; byte < 8; ++byte) {
    hash ^= (value >> (8 * byte)) & 0xffu;
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace canopy
