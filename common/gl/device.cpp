#include "common/gl/device.h"

#include <regex>
#include <stdexcept>

#include <fmt/format.h>
#include <glm/gtc/type_ptr.hpp>

namespace canopy::gl {

LedgerEntry& LedgerEntry::operator=(LedgerEntry&& other) noexcept {
  if (this != &other) {
    reset();
    mLedger = std::exchange(other.mLedger, nullptr);
    mId = std::exchange(other.mId, 0);
  }
  return *this;
}

void LedgerEntry::reset() {
  if (mLedger) mLedger->release(mId);
  mLedger = nullptr;
  mId = 0;
}

void deleteBufferName(GLuint id) {
  api().DeleteBuffers(1, &id);
}
void deleteTextureName(GLuint id) {
  api().DeleteTextures(1, &id);
}
void deleteVertexArrayName(GLuint id) {
  api().DeleteVertexArrays(1, &id);
}
void deleteFramebufferName(GLuint id) {
  api().DeleteFramebuffers(1, &id);
}
void deleteRenderbufferName(GLuint id) {
  api().DeleteRenderbuffers(1, &id);
}
void deleteProgramName(GLuint id) {
  api().DeleteProgram(id);
}

Buffer Device::createBuffer(MemoryCategory category, GLenum target, size_t bytes, const void* data,
                            std::string label, GLenum usage) {
  const Api& g = api();
  GLuint id = 0;
  g.GenBuffers(1, &id);
  Buffer buffer;
  buffer.name = GlName<deleteBufferName>(id);
  g.BindBuffer(target, id);
  g.BufferData(target, static_cast<GLsizeiptr>(bytes), data, usage);
  g.BindBuffer(target, 0);
  buffer.bytes = bytes;
  buffer.entry = LedgerEntry(&mLedger, mLedger.record(mOwner, category, bytes, std::move(label)));
  checkError("createBuffer");
  return buffer;
}

Texture Device::createTexture(const TextureDesc& desc) {
  const Api& g = api();
  GLuint id = 0;
  g.GenTextures(1, &id);
  Texture texture;
  texture.name = GlName<deleteTextureName>(id);
  texture.desc = desc;
  texture.levels = desc.mipmaps ? fullMipLevelCount(desc.width, desc.height) : 1;
  // Format and type of the (absent) client data only matter for validation of the call.
  const bool integer = desc.internalFormat == GL_R32UI || desc.internalFormat == GL_RG32UI ||
                       desc.internalFormat == GL_RGBA32UI || desc.internalFormat == GL_RGBA16UI ||
                       desc.internalFormat == GL_R16UI || desc.internalFormat == GL_RGBA8UI ||
                       desc.internalFormat == GL_R8UI || desc.internalFormat == GL_RG16UI;
  const bool depth =
      desc.internalFormat == GL_DEPTH_COMPONENT24 || desc.internalFormat == GL_DEPTH_COMPONENT32F;
  const GLenum format = depth ? GL_DEPTH_COMPONENT : integer ? GL_RGBA_INTEGER : GL_RGBA;
  const GLenum type = depth ? GL_FLOAT : integer ? GL_UNSIGNED_INT : GL_UNSIGNED_BYTE;
  g.BindTexture(desc.target, id);
  uint64_t bytes = 0;
  for (int level = 0, w = desc.width, h = desc.height; level < texture.levels; ++level) {
    if (desc.target == GL_TEXTURE_2D_ARRAY) {
      g.TexImage3D(desc.target, level, static_cast<GLint>(desc.internalFormat), w, h, desc.layers,
                   0, format, type, nullptr);
    } else {
      g.TexImage2D(desc.target, level, static_cast<GLint>(desc.internalFormat), w, h, 0, format,
                   type, nullptr);
    }
    bytes += textureLevelBytes(desc.internalFormat, w, h, desc.layers);
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
  }
  g.TexParameteri(desc.target, GL_TEXTURE_BASE_LEVEL, 0);
  g.TexParameteri(desc.target, GL_TEXTURE_MAX_LEVEL, texture.levels - 1);
  g.BindTexture(desc.target, 0);
  texture.entry = LedgerEntry(&mLedger, mLedger.record(mOwner, desc.category, bytes, desc.label));
  checkError("createTexture");
  return texture;
}

void Device::uploadTexture(Texture& texture, GLenum format, GLenum type, const void* pixels) {
  const Api& g = api();
  const TextureDesc& d = texture.desc;
  g.BindTexture(d.target, texture.id());
  g.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  if (d.target == GL_TEXTURE_2D_ARRAY) {
    g.TexSubImage3D(d.target, 0, 0, 0, 0, d.width, d.height, d.layers, format, type, pixels);
  } else {
    g.TexSubImage2D(d.target, 0, 0, 0, d.width, d.height, format, type, pixels);
  }
  g.BindTexture(d.target, 0);
  if (texture.levels > 1) generateMipmaps(texture);
  checkError("uploadTexture");
}

void Device::uploadTextureLayer(Texture& texture, int layer, GLenum format, GLenum type,
                                const void* pixels, int level) {
  const Api& g = api();
  const TextureDesc& d = texture.desc;
  const int w = std::max(1, d.width >> level), h = std::max(1, d.height >> level);
  g.BindTexture(d.target, texture.id());
  g.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  g.TexSubImage3D(d.target, level, 0, 0, layer, w, h, 1, format, type, pixels);
  g.BindTexture(d.target, 0);
  checkError("uploadTextureLayer");
}

void Device::uploadTextureLevel(Texture& texture, int level, GLenum format, GLenum type,
                                const void* pixels) {
  const Api& g = api();
  const TextureDesc& d = texture.desc;
  const int w = std::max(1, d.width >> level), h = std::max(1, d.height >> level);
  g.BindTexture(d.target, texture.id());
  g.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  g.TexSubImage2D(d.target, level, 0, 0, w, h, format, type, pixels);
  g.BindTexture(d.target, 0);
  checkError("uploadTextureLevel");
}

void Device::uploadCompressedLevel(Texture& texture, int level, int layer,
                                   const std::vector<uint8_t>& blocks) {
  const Api& g = api();
  const TextureDesc& d = texture.desc;
  const int w = std::max(1, d.width >> level), h = std::max(1, d.height >> level);
  if (blocks.size() != textureLevelBytes(d.internalFormat, w, h, 1)) {
    throw std::logic_error("uploadCompressedLevel: block data does not match the level size");
  }
  g.BindTexture(d.target, texture.id());
  if (d.target == GL_TEXTURE_2D_ARRAY) {
    g.CompressedTexSubImage3D(d.target, level, 0, 0, layer, w, h, 1, d.internalFormat,
                              static_cast<GLsizei>(blocks.size()), blocks.data());
  } else {
    g.CompressedTexSubImage2D(d.target, level, 0, 0, w, h, d.internalFormat,
                              static_cast<GLsizei>(blocks.size()), blocks.data());
  }
  g.BindTexture(d.target, 0);
  checkError("uploadCompressedLevel");
}

void Device::generateMipmaps(Texture& texture) {
  const Api& g = api();
  g.BindTexture(texture.desc.target, texture.id());
  g.GenerateMipmap(texture.desc.target);
  g.BindTexture(texture.desc.target, 0);
}

RenderTarget Device::createRenderTarget(int width, int height, GLenum colorFormat) {
  const Api& g = api();
  RenderTarget target;
  target.width = width;
  target.height = height;
  target.color = createTexture({GL_TEXTURE_2D, width, height, 1, colorFormat, false,
                                MemoryCategory::kOther, "render target colour"});
  setTextureSampling(target.color, false, false);
  GLuint depth = 0;
  g.GenRenderbuffers(1, &depth);
  target.depth = GlName<deleteRenderbufferName>(depth);
  g.BindRenderbuffer(GL_RENDERBUFFER, depth);
  g.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  target.depthEntry = LedgerEntry(
      &mLedger, mLedger.record(mOwner, MemoryCategory::kOther,
                               textureLevelBytes(GL_DEPTH_COMPONENT24, width, height, 1),
                               "render target depth"));
  GLuint framebuffer = 0;
  g.GenFramebuffers(1, &framebuffer);
  target.framebuffer = GlName<deleteFramebufferName>(framebuffer);
  g.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  g.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, target.color.id(), 0);
  g.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  const GLenum status = g.CheckFramebufferStatus(GL_FRAMEBUFFER);
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw std::runtime_error(
        fmt::format("render target {}x{} incomplete (0x{:x})", width, height, status));
  }
  checkError("createRenderTarget");
  return target;
}

VertexArray createVertexArray() {
  const Api& g = api();
  GLuint id = 0;
  g.GenVertexArrays(1, &id);
  VertexArray vao{GlName<deleteVertexArrayName>(id)};
  g.BindVertexArray(id);
  return vao;
}

ShadowMap Device::createShadowMap(int size) {
  const Api& g = api();
  ShadowMap map;
  map.size = size;
  map.depth = createTexture({GL_TEXTURE_2D, size, size, 1, GL_DEPTH_COMPONENT24, false,
                             MemoryCategory::kOther, "shadow map"});
  g.BindTexture(GL_TEXTURE_2D, map.depth.id());
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  g.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  g.BindTexture(GL_TEXTURE_2D, 0);
  GLuint framebuffer = 0;
  g.GenFramebuffers(1, &framebuffer);
  map.framebuffer = GlName<deleteFramebufferName>(framebuffer);
  g.BindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  g.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, map.depth.id(), 0);
  const GLenum none = GL_NONE;
  g.DrawBuffers(1, &none);
  g.ReadBuffer(GL_NONE);
  const GLenum status = g.CheckFramebufferStatus(GL_FRAMEBUFFER);
  g.BindFramebuffer(GL_FRAMEBUFFER, 0);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error(fmt::format("shadow map {}² incomplete (0x{:x})", size, status));
  checkError("createShadowMap");
  return map;
}

void setTextureSampling(const Texture& texture, bool linear, bool repeat) {
  const Api& g = api();
  const GLenum target = texture.desc.target;
  g.BindTexture(target, texture.id());
  const bool mips = texture.levels > 1;
  g.TexParameteri(target, GL_TEXTURE_MIN_FILTER,
                  linear ? (mips ? GL_LINEAR_MIPMAP_LINEAR : GL_LINEAR)
                         : (mips ? GL_NEAREST_MIPMAP_NEAREST : GL_NEAREST));
  g.TexParameteri(target, GL_TEXTURE_MAG_FILTER, linear ? GL_LINEAR : GL_NEAREST);
  const GLint wrap = repeat ? GL_REPEAT : GL_CLAMP_TO_EDGE;
  g.TexParameteri(target, GL_TEXTURE_WRAP_S, wrap);
  g.TexParameteri(target, GL_TEXTURE_WRAP_T, wrap);
  g.BindTexture(target, 0);
}

namespace {

// Rewrites driver log lines so they name the shader file: Mesa writes "0:12(5): error",
// NVIDIA "0(12) : error"; the leading number is the source string, which expandIncludes maps
// to a file (0 the stage's own, k the k-th include).
std::string nameFileInLog(const std::vector<std::string_view>& paths, const std::string& log) {
  static const std::regex mesa(R"((^|\n)(\d+):(\d+)\((\d+)\))");
  static const std::regex nvidia(R"((^|\n)(\d+)\((\d+)\) ?)");
  const auto fileOf = [&](const std::string& number) {
    const size_t index = std::stoul(number);
    return std::string(index < paths.size() ? paths[index] : paths[0]);
  };
  const auto rewrite = [&](const std::string& source, const std::regex& pattern, bool column) {
    std::string result;
    auto begin = source.cbegin();
    std::smatch m;
    while (std::regex_search(begin, source.cend(), m, pattern)) {
      result.append(begin, m[0].first);
      result += m[1].str() + fileOf(m[2].str()) + ":" + m[3].str() +
                (column ? ":" + m[4].str() : std::string());
      begin = m[0].second;
    }
    result.append(begin, source.cend());
    return result;
  };
  return rewrite(rewrite(log, mesa, true), nvidia, false);
}

// Replaces each `#include "path"` line by the embedded file (one level), numbered as its own
// source string so compile errors name it, then restores the including file's numbering.
std::string expandIncludes(const ShaderSource& stage, std::vector<std::string_view>& paths) {
  static const std::regex include(R"re(^\s*#include\s+"([^"]+)"\s*$)re");
  paths = {stage.path};
  std::string out;
  size_t lineNumber = 0, start = 0;
  const std::string text(stage.text);
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    ++lineNumber;
    std::smatch match;
    if (std::regex_match(line, match, include)) {
      const ShaderSource& included = embeddedShader(match[1].str());
      const std::string includedText(included.text);
      if (std::regex_search(includedText, std::regex(R"re((^|\n)\s*#include\s)re")))
        throw std::logic_error(fmt::format("{}: nested #include", included.path));
      paths.push_back(included.path);
      out += fmt::format("#line 1 {}\n{}\n#line {} 0\n", paths.size() - 1, included.text,
                         lineNumber + 1);
    } else {
      out += line;
      out += '\n';
    }
    start = end + 1;
  }
  return out;
}

GLenum stageOf(std::string_view path) {
  if (path.ends_with(".vert")) return GL_VERTEX_SHADER;
  if (path.ends_with(".frag")) return GL_FRAGMENT_SHADER;
  if (path.ends_with(".geom")) return GL_GEOMETRY_SHADER;
  if (path.ends_with(".comp")) return GL_COMPUTE_SHADER;
  throw std::logic_error(fmt::format("{}: unknown shader stage extension", path));
}

}  // namespace

std::string withDefines(std::string_view text, std::string_view defines) {
  std::string out(text);
  const size_t newline = out.find('\n');
  out.insert(newline == std::string::npos ? out.size() : newline + 1, defines);
  return out;
}

namespace {
bool gLitVariant = false;
constexpr std::string_view kLightingInclude = "methods/common/lighting.glsl";

// Compiles and links `stages` (with `define` inserted after each #version line); sets
// `usesLighting` when a stage includes the shared lighting code.
GlName<deleteProgramName> buildProgram(const std::vector<ShaderSource>& stages,
                                       const std::string& define, bool* usesLighting) {
  const Api& g = api();
  GlName<deleteProgramName> program(g.CreateProgram());
  std::vector<GLuint> shaders;
  std::string names;
  for (const ShaderSource& stage : stages) {
    const GLuint shader = g.CreateShader(stageOf(stage.path));
    std::vector<std::string_view> sourcePaths;
    std::string expanded = expandIncludes(stage, sourcePaths);
    for (std::string_view path : sourcePaths)
      if (path == kLightingInclude && usesLighting) *usesLighting = true;
    if (!define.empty()) expanded = withDefines(expanded, fmt::format("{}\n#line 2 0\n", define));
    const GLchar* text = expanded.data();
    const auto length = static_cast<GLint>(expanded.size());
    g.ShaderSource(shader, 1, &text, &length);
    g.CompileShader(shader);
    GLint ok = 0;
    g.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      GLint logLength = 0;
      g.GetShaderiv(shader, GL_INFO_LOG_LENGTH, &logLength);
      std::string log(std::max(logLength, 1), '\0');
      g.GetShaderInfoLog(shader, logLength, nullptr, log.data());
      g.DeleteShader(shader);
      for (GLuint s : shaders) g.DeleteShader(s);
      throw std::runtime_error(
          fmt::format("shader compile error: {}", nameFileInLog(sourcePaths, log.c_str())));
    }
    g.AttachShader(program.id(), shader);
    shaders.push_back(shader);
    names += std::string(names.empty() ? "" : " + ") + std::string(stage.path);
  }
  g.LinkProgram(program.id());
  for (GLuint s : shaders) g.DeleteShader(s);
  GLint linked = 0;
  g.GetProgramiv(program.id(), GL_LINK_STATUS, &linked);
  if (!linked) {
    GLint logLength = 0;
    g.GetProgramiv(program.id(), GL_INFO_LOG_LENGTH, &logLength);
    std::string log(std::max(logLength, 1), '\0');
    g.GetProgramInfoLog(program.id(), logLength, nullptr, log.data());
    throw std::runtime_error(fmt::format("shader link error in {}: {}", names, log.c_str()));
  }
  return program;
}
}  // namespace

void selectLitVariant(bool lit) {
  gLitVariant = lit;
}
bool litVariantSelected() {
  return gLitVariant;
}

Program Device::createProgram(const std::vector<ShaderSource>& stages) {
  Program program;
  bool usesLighting = false;
  program.mName = buildProgram(stages, "", &usesLighting);
  if (usesLighting) program.mLitName = buildProgram(stages, "#define CANOPY_LIT 1", nullptr);
  return program;
}

void Program::use() const {
  api().UseProgram(id());
}

GLint Program::location(const char* uniform) const {
  auto& cache = id() == mName.id() ? mLocations : mLitLocations;
  auto it = cache.find(uniform);
  if (it == cache.end()) it = cache.emplace(uniform, api().GetUniformLocation(id(), uniform)).first;
  return it->second;
}

void Program::set(const char* uniform, int value) const {
  api().Uniform1i(location(uniform), value);
}
void Program::set(const char* uniform, float value) const {
  api().Uniform1f(location(uniform), value);
}
void Program::set(const char* uniform, const glm::vec2& v) const {
  api().Uniform2f(location(uniform), v.x, v.y);
}
void Program::set(const char* uniform, const glm::vec3& v) const {
  api().Uniform3f(location(uniform), v.x, v.y, v.z);
}
void Program::set(const char* uniform, const glm::vec4& v) const {
  api().Uniform4f(location(uniform), v.x, v.y, v.z, v.w);
}
void Program::set(const char* uniform, const glm::mat3& m) const {
  api().UniformMatrix3fv(location(uniform), 1, GL_FALSE, glm::value_ptr(m));
}
void Program::set(const char* uniform, const glm::mat4& m) const {
  api().UniformMatrix4fv(location(uniform), 1, GL_FALSE, glm::value_ptr(m));
}

}  // namespace canopy::gl
