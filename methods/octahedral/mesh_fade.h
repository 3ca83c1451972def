#pragma once

#include <memory>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "common/gl/device.h"
#include "methods/method.h"

namespace canopy {

// The polygonal mesh an impostor turns into near the camera, through a dithered cross-fade (as
// engines fade an impostor against its mesh): an instance whose bounding radius spans at least
// `meshPixels` output pixels is drawn as the reference mesh, one below meshPixels · (1 − band) as
// the impostor, one in between as both with complementary dither ranges (the mesh's share grows
// linearly with the radius in pixels). meshPixels = 0 turns the mesh off: nothing is baked or
// uploaded for it.
class MeshCrossFade {
 public:
  enum class State : uint8_t { kImpostor = 0, kFading = 1, kMesh = 2 };
  // An instance the impostor draws: its index in impostorBuffer() and the dither range it keeps.
  struct ImpostorDraw {
    GLint first = 0;
    GLsizei count = 0;
    glm::vec2 ditherKeep{0.0f, 1.0f};
  };

  MeshCrossFade(float meshPixels, float band);
  bool enabled() const { return mMeshPixels > 0.0f; }

  void bake(const Tree& tree, BakeContext& ctx);
  // `owner` is the ledger owner the per-frame instance buffers are charged to.
  void upload(gl::Device& device, std::string owner);
  void save(AssetFolder& asset) const;  // the mesh in the subfolder "mesh"
  void load(AssetFolder& asset);

  // Sorts the frame's instances by their bounding sphere (tree space: center, radius) in output
  // pixels, draws the mesh side and fills the impostor's draws (impostorBuffer()). Returns the
  // state of each instance in span order (the LoD signature's marks).
  const std::vector<State>& drawMeshSide(const FrameContext& frame,
                                         std::span<const Instance> instances, glm::vec3 center,
                                         float radius);
  GLuint impostorBuffer() const { return mImpostorBuffer.id(); }
  const std::vector<ImpostorDraw>& impostorDraws() const { return mImpostorDraws; }

  uint64_t leafPolygonsDrawn() const { return mLeafPolygonsDrawn; }
  // Instances drawn as mesh only, fading, impostor only in the last frame.
  std::vector<uint64_t> instancesPerState() const;

 private:
  void ensureCapacity(gl::Buffer& buffer, size_t& capacity, size_t matrices, const char* label);
  static void fill(const gl::Buffer& buffer, const std::vector<glm::mat4>& matrices);

  float mMeshPixels = 0.0f;
  float mBand = 0.25f;
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
