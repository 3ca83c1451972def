#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

namespace canopy::gl {

enum class MemoryCategory { kTexture, kGeometry, kOther };

struct MemoryTotals {
  uint64_t texture = 0;
  uint64_t geometry = 0;
  uint64_t other = 0;
  uint64_t total() const { return texture + geometry + other; }
  void add(MemoryCategory category, int64_t bytes);
};

// {"texture": …, "geometry": …, "other": …, "total": …} as in the results schema.
nlohmann::json toJson(const MemoryTotals& totals);

// Every GPU allocation is recorded here by owner (a method name, or "harness") and category.
// Memory figures are read from the ledger only; the sizes come from the allocation parameters
// (format, dimensions, mip levels), never from a number the measured method supplies.
class Ledger {
 public:
  using EntryId = uint64_t;

  EntryId record(std::string owner, MemoryCategory category, uint64_t bytes, std::string label);
  void release(EntryId id);
  MemoryTotals totals(std::string_view owner) const;
  MemoryTotals totalsAll() const;
  size_t liveEntries() const;

 private:
  struct Entry {
    std::string owner;
    MemoryCategory category;
    uint64_t bytes;
    std::string label;
  };
  mutable std::mutex mMutex;
  EntryId mNextId = 1;
  std::map<EntryId, Entry> mEntries;
};

// Bytes of one image level of an uncompressed or block-compressed internal format.
uint64_t textureLevelBytes(uint32_t internalFormat, int width, int height, int layers);
// Number of levels of a full mip chain down to 1×1.
int fullMipLevelCount(int width, int height);

}  // namespace canopy::gl
