#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "methods/multilayer_indirect/layered_billboard.h"

namespace canopy {

// How the multi-layer method's textures index each other; the shader reads the same constants.
inline constexpr int kRecordsPerRow = 1024;  // records texture: 3 texels a record
inline constexpr int kRecordTexels = 3;
inline constexpr int kListsWidth = 4096;  // lists texture: one entry a texel
inline constexpr uint32_t kMaxListStart = 1u << 24;

// The Hash, Lists and records textures of a set of layered billboards, packed as §6 describes
// (all Hash Textures in one atlas, all lists in one atlas), with the records the lists name kept
// once per leaf and billboard: a list entry is the record's index relative to its billboard's
// first record, so one leaf that overlaps eight cells is stored once, not eight times.
//
// A record is three texels. Float16 (RGBA16F): (centre.x, centre.y, height, image),
// (axisU.x, axisU.y, axisV.x, axisV.y), (axisU.z, axisV.z, 0, 0). 8-bit (RGBA8): the centre as
// two 16-bit fractions of the billboard's half extents (high and low bytes), the four in-plane
// axis components as signed bytes of `axisScale`, then (height / heightScale, axisU.z, axisV.z
// as signed bytes, image); a signed byte b stands for (b − 128) / 127.
struct ListTextures {
  bool eightBit = false;
  glm::ivec2 hashSize{1, 1};
  std::vector<uint32_t> hash;           // R32UI: (first list entry << 8) | length, 0 when empty
  std::vector<glm::ivec2> hashOrigins;  // per billboard (zero for those without lists)
  std::vector<uint32_t> recordBase;     // per billboard: its first record
  bool wideLists = false;               // R32UI lists (a billboard has 65536 records or more)
  int listsHeight = 1;
  std::vector<uint32_t> lists;  // kListsWidth × listsHeight, uploaded as R16UI or R32UI
  size_t recordCount = 0;
  int recordsHeight = 1;
  std::vector<float> recordsHalf;    // float16 mode: RGBA texels (uploaded into RGBA16F)
  std::vector<uint8_t> recordsByte;  // 8-bit mode: RGBA8 texels
  std::vector<uint8_t> ambient;      // float16 mode: RGBA8 per record, AO at the leaf corners
  std::vector<uint16_t> ambient4;    // 8-bit mode: RGBA4 per record
  float axisScale = 1.0f;            // 8-bit mode: the axes' component range
  float heightScale = 1.0f;          // 8-bit mode: the heights' range
  size_t listEntries = 0;
  size_t longestList = 0;
  size_t droppedEntries = 0;

  // GPU bytes of what packs() fills, by texture (the ledger counts the same formats).
  size_t bytes() const;
};

// Packs the first `withLists` billboards' hash grids, lists and records; billboards after them
// (the far cloud, which draws its low-resolution texture only) get none. InputError when the
// lists outgrow the 24-bit list start, or the 8-bit records' 256 images.
ListTextures packListTextures(const std::vector<LayeredBillboard>& layered, size_t withLists,
                              bool eightBit, size_t images);

// The record `r` as the shader decodes it from the packed texels (for checks and tests).
LeafRecord decodeRecord(const ListTextures& textures, size_t r, glm::vec2 halfExtents);

}  // namespace canopy
