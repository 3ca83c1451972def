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
                          const Aabb& treeBounds, const std::vector<float>& thresholds,
                          const Grouping& group, int groups) {
  const int levels = static_cast<int>(thresholds.size()) + 1;
  const float radius = 0.5f * glm::length(treeBounds.extent());
  groups = group ? std::max(groups, 1) : 1;
  // [level * groups + group]: the instances keep their order (nearest first) within each.
  std::vector<std::vector<glm::mat4>> byGroup(size_t(levels) * groups);
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
    level = std::min(level, levels - 1);
    const int g = group ? std::clamp(group(level, model), 0, groups - 1) : 0;
    byGroup[size_t(level) * groups + g].push_back(model);
    mSignature = fnv1aMix(mSignature, uint64_t(level));
  }
  mMatrices.clear();
  mRanges.assign(levels, Range{});
  mGroupRanges.assign(levels, std::vector<Range>(groups));
  for (int level = 0; level < levels; ++level) {
    mRanges[level].first = static_cast<GLint>(mMatrices.size());
    for (int g = 0; g < groups; ++g) {
      const std::vector<glm::mat4>& part = byGroup[size_t(level) * groups + g];
      mGroupRanges[level][g] = {static_cast<GLint>(mMatrices.size()),
                                static_cast<GLsizei>(part.size())};
      mMatrices.insert(mMatrices.end(), part.begin(), part.end());
    }
    mRanges[level].count = static_cast<GLsizei>(mMatrices.size()) - mRanges[level].first;
  }
  mBuffer.upload(*mDevice, mOwner, mMatrices, "per-frame instance lists");
}

}  // namespace canopy
