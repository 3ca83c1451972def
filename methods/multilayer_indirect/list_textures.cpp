#include "methods/multilayer_indirect/list_textures.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "methods/common/leaf_capture.h"

namespace canopy {
namespace {

uint8_t signedByte(float value) {
  return static_cast<uint8_t>(std::clamp(std::lround(value * 127.0f) + 128, 1L, 255L));
}
float fromSignedByte(uint8_t byte) {
  return (float(byte) - 128.0f) / 127.0f;
}

uint16_t unitWord(float value) {  // [−1, 1] to 16 bits
  return static_cast<uint16_t>(
      std::lround(std::clamp((value + 1.0f) * 0.5f, 0.0f, 1.0f) * 65535.0f));
}
float fromUnitWord(uint16_t word) {
  return float(word) / 65535.0f * 2.0f - 1.0f;
}

template <typename T>
T* texelOf(RecordPlane& plane, size_t record) {
  return reinterpret_cast<T*>(plane.data.data() + record * size_t(plane.bytesPerTexel));
}
template <typename T>
const T* texelOf(const RecordPlane& plane, size_t record) {
  return reinterpret_cast<const T*>(plane.data.data() + record * size_t(plane.bytesPerTexel));
}

}  // namespace

std::vector<RecordPlane> emptyRecordPlanes(bool eightBit, int rows) {
  std::vector<RecordPlane> planes;
  if (eightBit) {
    planes = {{"records_a", GL_RGBA16UI, GL_RGBA_INTEGER, GL_UNSIGNED_SHORT, 8, {}},
              {"records_b", GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4, {}},
              {"ambient_4bit", GL_RGBA4, GL_RGBA, GL_UNSIGNED_SHORT_4_4_4_4, 2, {}}};
  } else {
    planes = {{"records_a", GL_RGBA16F, GL_RGBA, GL_FLOAT, 16, {}},
              {"records_b", GL_RGBA16F, GL_RGBA, GL_FLOAT, 16, {}},
              {"records_c", GL_RG16F, GL_RG, GL_FLOAT, 8, {}},
              {"ambient", GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, 4, {}}};
  }
  for (RecordPlane& plane : planes)
    plane.data.assign(size_t(kRecordsPerRow) * rows * plane.bytesPerTexel, 0);
  return planes;
}

ListTextures packListTextures(const std::vector<LayeredBillboard>& layered, size_t withLists,
                              bool eightBit, size_t images) {
  ListTextures out;
  out.eightBit = eightBit;
  if (eightBit && images > 256) {
    throwInputError(
        "multilayer_indirect: lists_precision \"8bit\" holds at most 256 leaf images, the tree "
        "has {}; use \"float16\"",
        images);
  }
  std::vector<glm::ivec2> cellSizes;
  for (size_t i = 0; i < layered.size(); ++i)
    cellSizes.push_back(i < withLists ? layered[i].cells : glm::ivec2(1));
  const AtlasLayout hashLayout = packAtlas(cellSizes, 0, 1);
  out.hashSize = {hashLayout.width, hashLayout.height};
  out.hash.assign(size_t(hashLayout.width) * hashLayout.height, 0u);
  out.hashOrigins.assign(layered.size(), glm::ivec2(0));
  out.recordBase.assign(layered.size(), 0u);
  size_t records = 0;
  float axisScale = 0.0f, heightScale = 0.0f;
  for (size_t i = 0; i < withLists; ++i) {
    const LayeredBillboard& l = layered[i];
    out.recordBase[i] = static_cast<uint32_t>(records);
    out.wideLists = out.wideLists || l.records.size() >= 65536;
    records += l.records.size();
    for (const LeafRecord& record : l.records) {
      axisScale = std::max({axisScale, std::abs(record.axisU.x), std::abs(record.axisU.y),
                            std::abs(record.axisU.z), std::abs(record.axisV.x),
                            std::abs(record.axisV.y), std::abs(record.axisV.z)});
      heightScale = std::max(heightScale, std::abs(record.height));
    }
  }
  out.axisScale = std::max(axisScale, 1e-12f);
  out.heightScale = std::max(heightScale, 1e-12f);
  out.recordCount = records;
  out.recordsHeight =
      static_cast<int>(std::max<size_t>(1, (records + kRecordsPerRow - 1) / kRecordsPerRow));
  out.planes = emptyRecordPlanes(eightBit, out.recordsHeight);
  for (size_t i = 0; i < withLists; ++i) {
    const LayeredBillboard& l = layered[i];
    const auto base = static_cast<uint32_t>(out.lists.size());
    if (size_t(base) + l.entries.size() >= kMaxListStart)
      throwInputError("multilayer_indirect: more than 2^24 list entries; lower 'hash_resolution'");
    out.lists.insert(out.lists.end(), l.entries.begin(), l.entries.end());
    out.hashOrigins[i] = hashLayout.origins[i];
    for (int y = 0; y < l.cells.y; ++y) {
      for (int x = 0; x < l.cells.x; ++x) {
        const size_t cell = size_t(y) * l.cells.x + x;
        if (l.listLength[cell] == 0) continue;
        out.longestList = std::max<size_t>(out.longestList, l.listLength[cell]);
        out.hash[size_t(hashLayout.origins[i].y + y) * hashLayout.width + hashLayout.origins[i].x +
                 x] = ((base + l.listStart[cell]) << 8) | l.listLength[cell];
      }
    }
    out.droppedEntries += l.droppedEntries;
    for (size_t k = 0; k < l.records.size(); ++k) {
      const LeafRecord& r = l.records[k];
      const size_t index = out.recordBase[i] + k;
      if (!eightBit) {
        const float a[4] = {r.center.x, r.center.y, r.axisU.x, r.axisU.y};
        const float b[4] = {r.axisV.x, r.axisV.y, r.height, float(r.image)};
        const float c[2] = {r.axisU.z, r.axisV.z};
        std::copy(a, a + 4, texelOf<float>(out.planes[0], index));
        std::copy(b, b + 4, texelOf<float>(out.planes[1], index));
        std::copy(c, c + 2, texelOf<float>(out.planes[2], index));
        uint8_t* ambient = texelOf<uint8_t>(out.planes[3], index);
        for (int corner = 0; corner < 4; ++corner)
          ambient[corner] = static_cast<uint8_t>(std::lround(r.ambient[corner] * 255.0f));
        continue;
      }
      const float s = out.axisScale;
      const auto pair = [](uint8_t high, uint8_t low) { return uint16_t(high << 8 | low); };
      const uint16_t a[4] = {unitWord(r.center.x / l.halfExtents.x),
                             unitWord(r.center.y / l.halfExtents.y),
                             pair(signedByte(r.axisU.x / s), signedByte(r.axisU.y / s)),
                             pair(signedByte(r.axisV.x / s), signedByte(r.axisV.y / s))};
      const uint8_t b[4] = {signedByte(r.height / out.heightScale), signedByte(r.axisU.z / s),
                            signedByte(r.axisV.z / s), uint8_t(r.image)};
      std::copy(a, a + 4, texelOf<uint16_t>(out.planes[0], index));
      std::copy(b, b + 4, texelOf<uint8_t>(out.planes[1], index));
      uint16_t word = 0;
      for (int corner = 0; corner < 4; ++corner)
        word = uint16_t(word << 4 |
                        uint16_t(std::lround(std::clamp(r.ambient[corner], 0.0f, 1.0f) * 15.0f)));
      *texelOf<uint16_t>(out.planes[2], index) = word;
    }
  }
  out.listEntries = out.lists.size();
  out.listsHeight =
      static_cast<int>(std::max<size_t>(1, (out.lists.size() + kListsWidth - 1) / kListsWidth));
  out.lists.resize(size_t(kListsWidth) * out.listsHeight, 0u);
  return out;
}

LeafRecord decodeRecord(const ListTextures& textures, size_t r, glm::vec2 halfExtents) {
  LeafRecord record;
  if (!textures.eightBit) {
    const float* a = texelOf<float>(textures.planes[0], r);
    const float* b = texelOf<float>(textures.planes[1], r);
    const float* c = texelOf<float>(textures.planes[2], r);
    record.center = {a[0], a[1]};
    record.axisU = {a[2], a[3], c[0]};
    record.axisV = {b[0], b[1], c[1]};
    record.height = b[2];
    record.image = static_cast<uint32_t>(std::lround(b[3]));
    return record;
  }
  const uint16_t* a = texelOf<uint16_t>(textures.planes[0], r);
  const uint8_t* b = texelOf<uint8_t>(textures.planes[1], r);
  record.center = glm::vec2(fromUnitWord(a[0]), fromUnitWord(a[1])) * halfExtents;
  const float s = textures.axisScale;
  record.axisU = glm::vec3(fromSignedByte(uint8_t(a[2] >> 8)), fromSignedByte(uint8_t(a[2])),
                           fromSignedByte(b[1])) *
                 s;
  record.axisV = glm::vec3(fromSignedByte(uint8_t(a[3] >> 8)), fromSignedByte(uint8_t(a[3])),
                           fromSignedByte(b[2])) *
                 s;
  record.height = fromSignedByte(b[0]) * textures.heightScale;
  record.image = b[3];
  return record;
}

}  // namespace canopy
