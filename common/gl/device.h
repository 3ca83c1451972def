#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "common/gl/api.h"
#include "common/gl/ledger.h"

namespace canopy::gl {

// A ledger record that is released when its resource dies (movable, not copyable).
class LedgerEntry {
 public:
  LedgerEntry() = default;
  LedgerEntry(Ledger* ledger, Ledger::EntryId id) : mLedger(ledger), mId(id) {}
  LedgerEntry(LedgerEntry&& other) noexcept { *this = std::move(other); }
  LedgerEntry& operator=(LedgerEntry&& other) noexcept;
  ~LedgerEntry() { reset(); }
  void reset();

 private:
  Ledger* mLedger = nullptr;
  Ledger::EntryId mId = 0;
};

// A GL object name with its deleter; the base of every RAII wrapper below.
template <void (*Delete)(GLuint)>
class GlName {
 public:
  GlName() = default;
  explicit GlName(GLuint id) : mId(id) {}
  GlName(GlName&& other) noexcept : mId(std::exchange(other.mId, 0)) {}
  GlName& operator=(GlName&& other) noexcept {
    if (this != &other) {
      reset();
      mId = std::exchange(other.mId, 0);
    }
    return *this;
  }
  ~GlName() { reset(); }
  void reset() {
    if (mId != 0) Delete(mId);
    mId = 0;
  }
  GLuint id() const { return mId; }
  explicit operator bool() const { return mId != 0; }

 private:
  GLuint mId = 0;
};

void deleteBufferName(GLuint id);
void deleteTextureName(GLuint id);
void deleteVertexArrayName(GLuint id);
void deleteFramebufferName(GLuint id);
void deleteRenderbufferName(GLuint id);
void deleteProgramName(GLuint id);

struct Buffer {
  GlName<deleteBufferName> name;
  size_t bytes = 0;
  LedgerEntry entry;
  GLuint id() const { return name.id(); }
};

struct TextureDesc {
  GLenum target = GL_TEXTURE_2D;  // GL_TEXTURE_2D or GL_TEXTURE_2D_ARRAY
  int width = 1;
  int height = 1;
  int layers = 1;  // array layers (GL_TEXTURE_2D_ARRAY)
  GLenum internalFormat = GL_RGBA8;
  bool mipmaps = false;  // allocate the full chain (counted in the ledger)
  MemoryCategory category = MemoryCategory::kTexture;
  std::string label;  // what the texture is, for the ledger
};

struct Texture {
  GlName<deleteTextureName> name;
  TextureDesc desc;
  int levels = 1;
  LedgerEntry entry;
  GLuint id() const { return name.id(); }
};

struct VertexArray {
  GlName<deleteVertexArrayName> name;
  GLuint id() const { return name.id(); }
};

// A new vertex array, bound so its attribute setup can follow (attribute-less draws need one
// bound too in a core context). Vertex arrays hold no memory of their own, so no ledger entry.
VertexArray createVertexArray();

// An offscreen colour + depth target; colour is a texture so it can be read back or sampled.
struct RenderTarget {
  GlName<deleteFramebufferName> framebuffer;
  GlName<deleteRenderbufferName> depth;
  Texture color;
  int width = 0;
  int height = 0;
  LedgerEntry depthEntry;
};

// A depth texture (compare mode on, for sampler2DShadow) and its framebuffer: a directional
// light's shadow map.
struct ShadowMap {
  GlName<deleteFramebufferName> framebuffer;
  Texture depth;
  int size = 0;
};

struct ShaderSource {
  std::string_view path;  // source file relative to the repository, named in errors
  std::string_view text;
};

// Looks up a shader embedded at build time by its repository path; throws std::logic_error
// when no such file was embedded (a build mistake, not user input).
const ShaderSource& embeddedShader(std::string_view path);
// A shader's `text` with `defines` (whole lines, e.g. "#define X 1\n") after its #version line: a
// variant of one shader file. The caller keeps the string while a ShaderSource views it.
std::string withDefines(std::string_view text, std::string_view defines);

// Programs whose shaders include methods/common/lighting.glsl are built twice: unlit, and with
// CANOPY_LIT defined (lighting, AO, leaf normals, shadow lookups). On a CPU rasteriser code
// behind a uniform branch still costs every fragment, so unlit frames must not carry it. The
// harness selects the variant per frame; Program::use/set/id follow the selection.
void selectLitVariant(bool lit);
bool litVariantSelected();

class Program {
 public:
  Program() = default;
  GLuint id() const { return litVariantSelected() && mLitName.id() ? mLitName.id() : mName.id(); }
  void use() const;
  GLint location(const char* uniform) const;  // -1 when the uniform is unused
  void set(const char* uniform, int value) const;
  void set(const char* uniform, float value) const;
  void set(const char* uniform, const glm::vec2& value) const;
  void set(const char* uniform, const glm::vec3& value) const;
  void set(const char* uniform, const glm::vec4& value) const;
  void set(const char* uniform, const glm::mat3& value) const;
  void set(const char* uniform, const glm::mat4& value) const;

 private:
  friend class Device;
  GlName<deleteProgramName> mName, mLitName;  // the second only with lighting.glsl
  mutable std::unordered_map<std::string, GLint> mLocations, mLitLocations;
};

// The methods' view of the GPU: every allocation goes through it and into the ledger under the
// current owner, which the harness sets (methods cannot choose whom they charge).
class Device {
 public:
  explicit Device(Ledger& ledger) : mLedger(ledger) {}

  Ledger& ledger() { return mLedger; }
  const std::string& owner() const { return mOwner; }

  // Sets the owner charged for allocations until the scope ends.
  class OwnerScope {
   public:
    OwnerScope(Device& device, std::string owner) : mDevice(device), mPrevious(device.mOwner) {
      device.mOwner = std::move(owner);
    }
    ~OwnerScope() { mDevice.mOwner = mPrevious; }

   private:
    Device& mDevice;
    std::string mPrevious;
  };

  Buffer createBuffer(MemoryCategory category, GLenum target, size_t bytes, const void* data,
                      std::string label, GLenum usage = GL_STATIC_DRAW);
  template <typename T>
  Buffer createBuffer(MemoryCategory category, GLenum target, const std::vector<T>& data,
                      std::string label) {
    return createBuffer(category, target, data.size() * sizeof(T), data.data(), std::move(label));
  }

  // Allocates storage (all levels when desc.mipmaps) and records it.
  Texture createTexture(const TextureDesc& desc);
  // Uploads level 0 (all layers for arrays) from tightly packed pixels, then builds mipmaps.
  void uploadTexture(Texture& texture, GLenum format, GLenum type, const void* pixels);
  void uploadTextureLayer(Texture& texture, int layer, GLenum format, GLenum type,
                          const void* pixels, int level = 0);
  // Uploads one level (of one layer, for arrays) of a block-compressed texture.
  void uploadCompressedLevel(Texture& texture, int level, int layer,
                             const std::vector<uint8_t>& blocks);
  void generateMipmaps(Texture& texture);
  // Uploads one mip level of a 2D texture (levels made on the CPU, e.g. coverage-preserving).
  void uploadTextureLevel(Texture& texture, int level, GLenum format, GLenum type,
                          const void* pixels);

  RenderTarget createRenderTarget(int width, int height, GLenum colorFormat);
  ShadowMap createShadowMap(int size);

  Program createProgram(const std::vector<ShaderSource>& stages);

 private:
  Ledger& mLedger;
  std::string mOwner = "unowned";
};

void setTextureSampling(const Texture& texture, bool linear, bool repeat);

}  // namespace canopy::gl
