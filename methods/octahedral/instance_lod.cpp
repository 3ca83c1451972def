#include "methods/octahedral/instance_lod.h"

#include <algorithm>

#include <glm/geometric.hpp>

namespace canopy {

InstanceLod::InstanceLod(float meshPixels, float band, float blendPixels)
    : mMeshPixels(meshPixels), mBand(band), mBlendPixels(blendPixels) {
  // The reference at its defaults, through the registry: no method reaches into another's files.
  if (meshEnabled())
    mMesh = builtinMethods().find("polygonal").create(nlohmann::json::object(), "octahedral mesh");
}

void InstanceLod::bake(const Tree& tree, BakeContext& ctx) {
  if (meshEnabled()) mMesh->bake(tree, ctx);
}

void InstanceLod::upload(gl::Device& device, std::string owner) {
  mDevice = &device;
  mOwner = std::move(owner);
  if (meshEnabled()) mMesh->upload(device);
}

void InstanceLod::save(AssetFolder& asset) const {
  if (!meshEnabled()) return;
  AssetFolder mesh(asset.folder() / "mesh");
  std::filesystem::create_directories(mesh.folder());
  mMesh->save(mesh);
}

void InstanceLod::load(AssetFolder& asset) {
  if (!meshEnabled()) return;
  AssetFolder mesh(asset.folder() / "mesh");
  mMesh->load(mesh);
}

void InstanceLod::ensureCapacity(gl::Buffer& buffer, size_t& capacity, size_t matrices,
                                 const char* label) {
  if (matrices <= capacity && buffer.id()) return;
  capacity = std::max<size_t>(matrices, 16);
  gl::Device::OwnerScope scope(*mDevice, mOwner);
  buffer = mDevice->createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER,
                                 capacity * sizeof(glm::mat4), nullptr, label, GL_DYNAMIC_DRAW);
}

void InstanceLod::fill(const gl::Buffer& buffer, const std::vector<glm::mat4>& matrices) {
  const gl::Api& g = gl::api();
  g.BindBuffer(GL_ARRAY_BUFFER, buffer.id());
  g.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(matrices.size() * sizeof(glm::mat4)),
                  matrices.data());
  g.BindBuffer(GL_ARRAY_BUFFER, 0);
}

const std::vector<InstanceLod::State>& InstanceLod::sortAndDrawMesh(
    const FrameContext& frame, std::span<const Instance> instances, glm::vec3 center,
    float radius) {
  const float start = mMeshPixels * (1.0f - mBand);
  std::vector<Instance> meshOnly;
  std::vector<glm::mat4> blended, nearestFrame;
  struct Fading {
    Instance instance;
    float share;  // the mesh's
    int frames;   // the impostor's
  };
  std::vector<Fading> fading;
  mStates.clear();
  for (const Instance& instance : instances) {
    const glm::mat4 model = instance.modelMatrix();
    State state = State::kBlended;
    float share = 0.0f, pixels = 0.0f;
    if (frame.forcedLevel >= 0) {
      state = State(std::min(frame.forcedLevel, int(State::kNearestFrame)));
      share = state == State::kFading ? 0.5f : 0.0f;
    } else {
      const glm::vec3 centre = glm::vec3(model * glm::vec4(center, 1.0f));
      pixels = frame.projectedPixels(radius * instance.scale,
                                     glm::length(frame.cameraPosition - centre));
      if (meshEnabled())
        share = std::clamp((pixels - start) / std::max(mMeshPixels - start, 1e-6f), 0.0f, 1.0f);
      state = share >= 1.0f           ? State::kMesh
              : share > 0.0f          ? State::kFading
              : pixels < mBlendPixels ? State::kNearestFrame
                                      : State::kBlended;
    }
    if (!meshEnabled() && state <= State::kFading) state = State::kBlended;
    mStates.push_back(state);
    if (state == State::kMesh) meshOnly.push_back(instance);
    if (state == State::kFading) fading.push_back({instance, share, pixels < mBlendPixels ? 1 : 3});
    if (state == State::kBlended) blended.push_back(model);
    if (state == State::kNearestFrame) nearestFrame.push_back(model);
  }

  // The impostor's instances: blended ones, one-frame ones, then the fading ones one by one.
  mImpostorDraws.clear();
  std::vector<glm::mat4> impostorMatrices;
  for (const auto& [group, frames] : {std::pair{&blended, 3}, {&nearestFrame, 1}}) {
    if (group->empty()) continue;
    mImpostorDraws.push_back({static_cast<GLint>(impostorMatrices.size()),
                              static_cast<GLsizei>(group->size()),
                              frames,
                              {0.0f, 1.0f}});
    impostorMatrices.insert(impostorMatrices.end(), group->begin(), group->end());
  }
  for (const Fading& f : fading) {
    mImpostorDraws.push_back(
        {static_cast<GLint>(impostorMatrices.size()), 1, f.frames, {f.share, 1.0f}});
    impostorMatrices.push_back(f.instance.modelMatrix());
  }
  ensureCapacity(mImpostorBuffer, mImpostorCapacity, impostorMatrices.size(), "impostor instances");
  fill(mImpostorBuffer, impostorMatrices);

  // The mesh: every instance it draws whole in one call, then each fading one with its share.
  mLeafPolygonsDrawn = 0;
  if (!meshEnabled()) return mStates;
  ensureCapacity(mMeshBuffer, mMeshCapacity, std::max<size_t>(meshOnly.size(), 1),
                 "mesh instances");
  FrameContext meshFrame = frame;
  meshFrame.instanceBuffer = mMeshBuffer.id();
  const auto drawMesh = [&](std::span<const Instance> drawn, glm::vec2 keep) {
    std::vector<glm::mat4> matrices;
    for (const Instance& instance : drawn) matrices.push_back(instance.modelMatrix());
    fill(mMeshBuffer, matrices);
    meshFrame.ditherKeep = keep;
    mMesh->draw(meshFrame, drawn);
    mLeafPolygonsDrawn += mMesh->leafPolygonsDrawn();
  };
  if (!meshOnly.empty()) drawMesh(meshOnly, {0.0f, 1.0f});
  for (const Fading& f : fading) drawMesh({&f.instance, 1}, {0.0f, f.share});
  return mStates;
}

std::vector<uint64_t> InstanceLod::instancesPerState() const {
  std::vector<uint64_t> counts(4, 0);
  for (State state : mStates) ++counts[static_cast<int>(state)];
  return counts;
}

}  // namespace canopy
