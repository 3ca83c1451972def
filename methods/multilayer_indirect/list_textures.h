#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "common/gl/api.h"
#include "methods/multilayer_indirect/layered_billboard.h"

namespace canopy {

// How the multi-layer method's textures index each other; the shader reads the same constants.
inline constexpr int kRecordsPerRow = 1024;  // every record plane: one texel a record
inline constexpr int kListsWidth = 4096;     // lists texture: one entry a texel
inline constexpr uint32_t kMaxListStart = 1u << 24;

// One texture of the leaf records, a texel per record, rows of kRecordsPerRow.
struct RecordPlane {
  const char* name;       // the asset blob ("records_a.bin") and ledger label stem
  GLenum internalFormat;  // GPU storage
  GLenum format, type;    // how `data` is laid out for upload
  int bytesPerTexel;      // of `data`
  std::vector<uint8_t> data;
};

// The Hash, Lists and records textures of a set of layered billboards, packed as §6 describes
// (all Hash Textures in one atlas, all lists in one atlas), with the records the lists name kept
// once per leaf and billboard: a list entry is the record's index relative to its billboard's
// first record, so one leaf that overlaps eight cells is stored once, not eight times.
//
// A record is split over planes so that a list entry the fragment's point misses costs the list
// fetch and one record fetch (8-bit) or two (float16): the first plane holds what locating the
// point on the leaf needs.
// - 8-bit: A (RGBA16UI) = centre as two 16-bit fractions of the billboard's half extents, then
//   (axisU.x, axisU.y) and (axisV.x, axisV.y) as signed byte pairs of `axisScale`; B (RGBA8) =
//   height / heightScale, axisU.z, axisV.z as signed bytes, and the image; AO (RGBA4).
//   A signed byte b stands for (b − 128) / 127. 14 bytes a record.
// - float16: A (RGBA16F) = centre, axisU.xy; B (RGBA16F) = axisV.xy, height, image;
//   C (RG16F) = axisU.z, axisV.z; AO (RGBA8). 24 bytes a record.
// The parallax shader needs every plane for each entry; the paper's, A (and B) until it hits.
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
  std::vector<RecordPlane> planes;  // the record planes above, ambient occlusion last
  float axisScale = 1.0f;           // 8-bit mode: the axes' component range
  float heightScale = 1.0f;         // 8-bit mode: the heights' range
  size_t listEntries = 0;
  size_t longestList = 0;
  size_t droppedEntries = 0;
};

// The record planes of a mode, empty (`records` rows of kRecordsPerRow texels).
std::vector<RecordPlane> emptyRecordPlanes(bool eightBit, int rows);

// Packs the first `withLists` billboards' hash grids, lists and records; billboards after them
// (the far cloud, which draws its low-resolution texture only) get none. InputError when the
// lists outgrow the 24-bit list start, or the 8-bit records' 256 images.
ListTextures packListTextures(const std::vector<LayeredBillboard>& layered, size_t withLists,
                              bool eightBit, size_t images);

// The record `r` as the shader decodes it from the planes (for checks and tests).
LeafRecord decodeRecord(const ListTextures& textures, size_t r, glm::vec2 halfExtents);

}  // namespace canopy
