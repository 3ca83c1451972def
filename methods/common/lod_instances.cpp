#include "methods/common/lod_instances.h"

#include <algorithm>

#include <glm/geometric.hpp>

namespace canopy {

void StreamedMatrices::upload(gl::Device& device, const std::string& owner,
                              std::span<const glm::mat4> matrices, const char* label) {
  if (matrices.size() > mCapacity || !mBuffer.id()) {
    mCapacity = std::max<size_t>(matrices.size(), 16);
    gl::Device::OwnerScope scope(device, owner);
    mBuffer = device.createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER,
                                  mCapacity * sizeof(glm::mat4), nullptr, label, GL_DYNAMIC_DRAW);
  }
  if (matrices.empty()) return;
  const gl::Api& g = gl::api();
  g.BindBuffer(GL_ARRAY_BUFFER, mBuffer.id());
  g.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(matrices.size_bytes()),
                  matrices.data());
  g.BindBuffer(GL_ARRAY_BUFFER, 0);
}

void LodInstances::attach(gl::Device& device, std::string owner) {
  mDevice = &device;
  mOwner = std::move(owner);
}

int LodInstances::levelFor(float radiusPixels, const std::vector<float>& thresholds) {
  int level = 0;
  while (level < static_cast<int>(thresholds.size()) && radiusPixels < thresholds[level]) ++level;
  return level;
}

void LodInstances::update(const FrameContext& frame, std::span<const Instance> instances,
                          const Aabb& treeBounds, const std::vector<float>& thresholds) {
  const int levels = static_cast<int>(thresholds.size()) + 1;
  const float radius = 0.5f * glm::length(treeBounds.extent());
  std::vector<std::vector<glm::mat4>> byLevel(levels);
  mSignature = 0xcbf29ce484222325ull;
  for (const Instance& instance : instances) {
    const glm::mat4 model = instance.modelMatrix();
    int level = frame.forcedLevel;
    if (level < 0) {
      const glm::vec3 centre = glm::vec3(model * glm::vec4(treeBounds.center(), 1.0f));
      level = levelFor(frame.projectedPixels(radius * instance.scale,
                                             glm::length(frame.cameraPosition - centre)),
                       thresholds);
    }
    byLevel[std::min(level, levels - 1)].push_back(model);
    mSignature = fnv1aMix(mSignature, uint64_t(std::min(level, levels - 1)));
  }
  mMatrices.clear();
  mRanges.assign(levels, Range{});
  for (int level = 0; level < levels; ++level) {
    mRanges[level] = {static_cast<GLint>(mMatrices.size()),
                      static_cast<GLsizei>(byLevel[level].size())};
    mMatrices.insert(mMatrices.end(), byLevel[level].begin(), byLevel[level].end());
  }
  mBuffer.upload(*mDevice, mOwner, mMatrices, "per-frame instance lists");
}

}  // namespace canopy
