#pragma once

#include <memory>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "common/gl/device.h"
#include "methods/method.h"

namespace canopy {

// Each frame's instances sorted by the output pixels their bounding radius spans, largest first:
// the polygonal mesh (from `meshPixels` on), a dithered cross-fade between mesh and impostor
// (from meshPixels · (1 − band); the mesh's share grows linearly with the pixels), the impostor
// blending three frames, and below `blendPixels` the impostor's nearest frame alone (engines
// drop the blend for far impostors too). meshPixels = 0: no mesh, nothing baked or uploaded for
// it; blendPixels = 0: every impostor blends.
class InstanceLod {
 public:
  // Finest first (instancesPerState's order).
  enum class State : uint8_t { kMesh = 0, kFading = 1, kBlended = 2, kNearestFrame = 3 };
  // Impostor instances drawn in one call: from `first` in impostorBuffer(), with three frames
  // or one, keeping the dither range `ditherKeep`.
  struct ImpostorDraw {
    GLint first = 0;
    GLsizei count = 0;
    int frames = 3;
    glm::vec2 ditherKeep{0.0f, 1.0f};
  };

  InstanceLod(float meshPixels, float band, float blendPixels);
  bool meshEnabled() const { return mMeshPixels > 0.0f; }

  void bake(const Tree& tree, BakeContext& ctx);
  // `owner` is the ledger owner the per-frame instance buffers are charged to.
  void upload(gl::Device& device, std::string owner);
  void save(AssetFolder& asset) const;  // the mesh in the subfolder "mesh"
  void load(AssetFolder& asset);

  // Sorts the frame's instances by their bounding sphere (tree space: center, radius) in output
  // pixels, draws the mesh side and fills the impostor's draws (impostorBuffer()). Returns the
  // state of each instance in span order (the LoD signature's marks). frame.forcedLevel >= 0
  // puts every instance in that state.
  const std::vector<State>& sortAndDrawMesh(const FrameContext& frame,
                                            std::span<const Instance> instances, glm::vec3 center,
                                            float radius);
  GLuint impostorBuffer() const { return mImpostorBuffer.id(); }
  const std::vector<ImpostorDraw>& impostorDraws() const { return mImpostorDraws; }

  uint64_t leafPolygonsDrawn() const { return mLeafPolygonsDrawn; }
  // Instances in each state in the last frame, finest first.
  std::vector<uint64_t> instancesPerState() const;

 private:
  void ensureCapacity(gl::Buffer& buffer, size_t& capacity, size_t matrices, const char* label);
  static void fill(const gl::Buffer& buffer, const std::vector<glm::mat4>& matrices);

  float mMeshPixels = 0.0f;
  float mBand = 0.25f;
  float mBlendPixels = 0.0f;
  std::unique_ptr<Method> mMesh;
  gl::Device* mDevice = nullptr;
  std::string mOwner;
  gl::Buffer mMeshBuffer, mImpostorBuffer;
  size_t mMeshCapacity = 0, mImpostorCapacity = 0;
  std::vector<State> mStates;
  std::vector<ImpostorDraw> mImpostorDraws;
  uint64_t mLeafPolygonsDrawn = 0;
};

}  // namespace canopy
