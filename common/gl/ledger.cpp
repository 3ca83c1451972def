#include "common/gl/ledger.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "common/gl/api.h"

namespace canopy::gl {

void MemoryTotals::add(MemoryCategory category, int64_t bytes) {
  switch (category) {
    case MemoryCategory::kTexture:
      texture += bytes;
      break;
    case MemoryCategory::kGeometry:
      geometry += bytes;
      break;
    case MemoryCategory::kOther:
      other += bytes;
      break;
  }
}

nlohmann::json toJson(const MemoryTotals& totals) {
  return {{"texture", totals.texture},
          {"geometry", totals.geometry},
          {"other", totals.other},
          {"total", totals.total()}};
}

Ledger::EntryId Ledger::record(std::string owner, MemoryCategory category, uint64_t bytes,
                               std::string label) {
  std::lock_guard lock(mMutex);
  const EntryId id = mNextId++;
  mEntries.emplace(id, Entry{std::move(owner), category, bytes, std::move(label)});
  return id;
}

void Ledger::release(EntryId id) {
  std::lock_guard lock(mMutex);
  const size_t erased = mEntries.erase(id);
  assert(erased == 1 && "ledger entry released twice");
  (void)erased;
}

MemoryTotals Ledger::totals(std::string_view owner) const {
  std::lock_guard lock(mMutex);
  MemoryTotals totals;
  for (const auto& [id, entry] : mEntries) {
    if (entry.owner == owner) totals.add(entry.category, static_cast<int64_t>(entry.bytes));
  }
  return totals;
}

MemoryTotals Ledger::totalsAll() const {
  std::lock_guard lock(mMutex);
  MemoryTotals totals;
  for (const auto& [id, entry] : mEntries)
    totals.add(entry.category, static_cast<int64_t>(entry.bytes));
  return totals;
}

size_t Ledger::liveEntries() const {
  std::lock_guard lock(mMutex);
  return mEntries.size();
}

uint64_t textureLevelBytes(uint32_t internalFormat, int width, int height, int layers) {
  const auto blocks = [&](uint64_t bytesPerBlock) {
    return uint64_t((width + 3) / 4) * uint64_t((height + 3) / 4) * bytesPerBlock * layers;
  };
  const auto texels = uint64_t(width) * uint64_t(height) * uint64_t(layers);
  switch (internalFormat) {
    case GL_R8:
    case GL_R8UI:
    case GL_R8I:
      return texels;
    case GL_RG8:
    case GL_RGBA4:
    case GL_R16F:
    case GL_R16UI:
    case GL_R16I:
    case GL_R16:
      return texels * 2;
    case GL_RGB8:
    case GL_SRGB8:
      return texels * 3;
    case GL_RGBA8:
    case GL_SRGB8_ALPHA8:
    case GL_RG16F:
    case GL_R32F:
    case GL_R32UI:
    case GL_R32I:
    case GL_RG16UI:
    case GL_RGBA8UI:
    case GL_RGB10_A2:
    case GL_DEPTH_COMPONENT24:
    case GL_DEPTH24_STENCIL8:
    case GL_DEPTH_COMPONENT32F:
      return texels * 4;
    case GL_RGBA16F:
    case GL_RG32F:
    case GL_RG32UI:
    case GL_RGBA16UI:
    case GL_RGBA16:
      return texels * 8;
    case GL_RGB32F:
      return texels * 12;
    case GL_RGBA32F:
    case GL_RGBA32UI:
    case GL_RGBA32I:
      return texels * 16;
    case 0x83F0:
    case 0x83F1:
    case 0x8C4C:
    case 0x8C4D:
      return blocks(8);  // DXT1 / sRGB DXT1
    case 0x83F2:
    case 0x83F3:
    case 0x8C4E:
    case 0x8C4F:
      return blocks(16);  // DXT3/5, sRGB
    default:
      throw std::logic_error("ledger: unknown internal format; add it to textureLevelBytes");
  }
}

int fullMipLevelCount(int width, int height) {
  int levels = 1;
  for (int size = std::max(width, height); size > 1; size /= 2) ++levels;
  return levels;
}

}  // namespace canopy::gl
