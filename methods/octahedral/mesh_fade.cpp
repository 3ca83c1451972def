#include "methods/octahedral/mesh_fade.h"

#include <algorithm>

#include <glm/geometric.hpp>

#include "methods/polygonal/polygonal.h"

namespace canopy {

MeshCrossFade::MeshCrossFade(float meshPixels, float band) : mMeshPixels(meshPixels), mBand(band) {
  if (enabled()) mMesh = makePolygonalReference();
}

void MeshCrossFade::bake(const Tree& tree, BakeContext& ctx) {
  if (enabled()) mMesh->bake(tree, ctx);
}

void MeshCrossFade::upload(gl::Device& device, std::string owner) {
  if (!enabled()) return;
  mDevice = &device;
  mOwner = std::move(owner);
  mMesh->upload(device);
}

void MeshCrossFade::save(AssetFolder& asset) const {
  if (!enabled()) return;
  AssetFolder mesh(asset.folder() / "mesh");
  std::filesystem::create_directories(mesh.folder());
  mMesh->save(mesh);
}

void MeshCrossFade::load(AssetFolder& asset) {
  if (!enabled()) return;
  AssetFolder mesh(asset.folder() / "mesh");
  mMesh->load(mesh);
}

void MeshCrossFade::ensureCapacity(gl::Buffer& buffer, size_t& capacity, size_t matrices,
                                   const char* label) {
  if (matrices <= capacity && buffer.id()) return;
  capacity = std::max<size_t>(matrices, 16);
  gl::Device::OwnerScope scope(*mDevice, mOwner);
  buffer = mDevice->createBuffer(gl::MemoryCategory::kOther, GL_ARRAY_BUFFER,
                                 capacity * sizeof(glm::mat4), nullptr, label, GL_DYNAMIC_DRAW);
}

void MeshCrossFade::fill(const gl::Buffer& buffer, const std::vector<glm::mat4>& matrices) {
  const gl::Api& g = gl::api();
  g.BindBuffer(GL_ARRAY_BUFFER, buffer.id());
  g.BufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(matrices.size() * sizeof(glm::mat4)),
                  matrices.data());
  g.BindBuffer(GL_ARRAY_BUFFER, 0);
}

const std::vector<MeshCrossFade::State>& MeshCrossFade::drawMeshSide(
    const FrameContext& frame, std::span<const Instance> instances, glm::vec3 center,
    float radius) {
  const float start = mMeshPixels * (1.0f - mBand);
  std::vector<Instance> meshOnly;
  std::vector<glm::mat4> impostorOnly;
  std::vector<std::pair<Instance, float>> fading;  // with the mesh's share
  mStates.clear();
  for (const Instance& instance : instances) {
    const glm::mat4 model = instance.modelMatrix();
    float share = frame.forcedLevel == 0 ? 1.0f : 0.0f;
    if (frame.forcedLevel < 0) {
      const glm::vec3 centre = glm::vec3(model * glm::vec4(center, 1.0f));
      const float pixels = frame.projectedPixels(radius * instance.scale,
                                                 glm::length(frame.cameraPosition - centre));
      share = std::clamp((pixels - start) / std::max(mMeshPixels - start, 1e-6f), 0.0f, 1.0f);
    }
    if (share >= 1.0f) {
      meshOnly.push_back(instance);
      mStates.push_back(State::kMesh);
    } else if (share <= 0.0f) {
      impostorOnly.push_back(model);
      mStates.push_back(State::kImpostor);
    } else {
      fading.emplace_back(instance, share);
      mStates.push_back(State::kFading);
    }
  }

  // The impostor's instances: those it draws alone, then the fading ones one by one.
  mImpostorDraws.clear();
  std::vector<glm::mat4> impostorMatrices = impostorOnly;
  if (!impostorOnly.empty())
    mImpostorDraws.push_back({0, static_cast<GLsizei>(impostorOnly.size()), {0.0f, 1.0f}});
  for (const auto& [instance, share] : fading) {
    mImpostorDraws.push_back({static_cast<GLint>(impostorMatrices.size()), 1, {share, 1.0f}});
    impostorMatrices.push_back(instance.modelMatrix());
  }
  ensureCapacity(mImpostorBuffer, mImpostorCapacity, impostorMatrices.size(), "impostor instances");
  fill(mImpostorBuffer, impostorMatrices);

  // The mesh: every instance it draws whole in one call, then each fading one with its share.
  mLeafPolygonsDrawn = 0;
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
  for (const auto& [instance, share] : fading) drawMesh({&instance, 1}, {0.0f, share});
  return mStates;
}

std::vector<uint64_t> MeshCrossFade::instancesPerState() const {
  std::vector<uint64_t> counts(3, 0);
  for (State state : mStates) ++counts[2 - static_cast<int>(state)];
  return counts;
}

}  // namespace canopy
