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

size_t texelOf(size_t record, int texel) {
  return (record / kRecordsPerRow) * (kRecordsPerRow * kRecordTexels) +
         (record % kRecordsPerRow) * kRecordTexels + size_t(texel);
}

}  // namespace

size_t ListTextures::bytes() const {
  const size_t listsBytes = size_t(kListsWidth) * listsHeight * (wideLists ? 4 : 2);
  const size_t recordTexels = size_t(kRecordsPerRow) * kRecordTexels * recordsHeight;
  const size_t ambientTexels = size_t(kRecordsPerRow) * recordsHeight;
  return hash.size() * 4 + listsBytes + recordTexels * (eightBit ? 4 : 8) +
         ambientTexels * (eightBit ? 2 : 4);
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
  const size_t recordTexels = size_t(kRecordsPerRow) * kRecordTexels * out.recordsHeight;
  const size_t ambientTexels = size_t(kRecordsPerRow) * out.recordsHeight;
  if (eightBit) {
    out.recordsByte.assign(recordTexels * 4, 0);
    out.ambient4.assign(ambientTexels, 0xffff);
  } else {
    out.recordsHalf.assign(recordTexels * 4, 0.0f);
    out.ambient.assign(ambientTexels * 4, 255);
  }
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
      float* half = eightBit ? nullptr : &out.recordsHalf[texelOf(index, 0) * 4];
      if (half) {
        const float texels[12] = {r.center.x, r.center.y, r.height,  float(r.image),
                                  r.axisU.x,  r.axisU.y,  r.axisV.x, r.axisV.y,
                                  r.axisU.z,  r.axisV.z,  0.0f,      0.0f};
        std::copy(texels, texels + 12, half);
        for (int c = 0; c < 4; ++c)
          out.ambient[index * 4 + c] = static_cast<uint8_t>(std::lround(r.ambient[c] * 255.0f));
        continue;
      }
      uint8_t* bytes = &out.recordsByte[texelOf(index, 0) * 4];
      const uint16_t cx = unitWord(r.center.x / l.halfExtents.x);
      const uint16_t cy = unitWord(r.center.y / l.halfExtents.y);
      const float s = out.axisScale;
      const uint8_t texels[12] = {uint8_t(cx >> 8),
                                  uint8_t(cx & 255),
                                  uint8_t(cy >> 8),
                                  uint8_t(cy & 255),
                                  signedByte(r.axisU.x / s),
                                  signedByte(r.axisU.y / s),
                                  signedByte(r.axisV.x / s),
                                  signedByte(r.axisV.y / s),
                                  signedByte(r.height / out.heightScale),
                                  signedByte(r.axisU.z / s),
                                  signedByte(r.axisV.z / s),
                                  uint8_t(r.image)};
      std::copy(texels, texels + 12, bytes);
      uint16_t word = 0;
      for (int c = 0; c < 4; ++c)
        word = uint16_t(word << 4 |
                        uint16_t(std::lround(std::clamp(r.ambient[c], 0.0f, 1.0f) * 15.0f)));
      out.ambient4[index] = word;
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
    const float* t = &textures.recordsHalf[texelOf(r, 0) * 4];
    record.center = {t[0], t[1]};
    record.height = t[2];
    record.image = static_cast<uint32_t>(std::lround(t[3]));
    record.axisU = {t[4], t[5], t[8]};
    record.axisV = {t[6], t[7], t[9]};
    return record;
  }
  const uint8_t* t = &textures.recordsByte[texelOf(r, 0) * 4];
  record.center = glm::vec2(fromUnitWord(uint16_t(t[0] << 8 | t[1])),
                            fromUnitWord(uint16_t(t[2] << 8 | t[3]))) *
                  halfExtents;
  const float s = textures.axisScale;
  record.axisU = glm::vec3(fromSignedByte(t[4]), fromSignedByte(t[5]), fromSignedByte(t[9])) * s;
  record.axisV = glm::vec3(fromSignedByte(t[6]), fromSignedByte(t[7]), fromSignedByte(t[10])) * s;
  record.height = fromSignedByte(t[8]) * textures.heightScale;
  record.image = t[11];
  return record;
}

}  // namespace canopy
