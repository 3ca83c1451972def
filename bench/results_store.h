#pragma once

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace canopy {

// results/<experiment>/metrics.jsonl: one JSON record per line, appended durably. On open, a
// torn last line (a run killed mid-write) is cut off, so the file holds only whole records, and
// the keys of the records present let a rerun skip what is done.
class ResultsStore {
 public:
  explicit ResultsStore(std::filesystem::path directory);

  const std::filesystem::path& directory() const { return mDirectory; }
  std::filesystem::path metricsPath() const { return mDirectory / "metrics.jsonl"; }
  bool has(const std::string& key) const { return mKeys.contains(key); }
  // The record appended under `key`, or nullptr.
  const nlohmann::json* find(const std::string& key) const;
  // Adds "record_key" to the record and appends it.
  void append(nlohmann::json record, const std::string& key);
  const std::vector<nlohmann::json>& records() const { return mRecords; }

  // Reads a metrics.jsonl (whole lines only).
  static std::vector<nlohmann::json> readRecords(const std::filesystem::path& path);

 private:
  std::filesystem::path mDirectory;
  std::vector<nlohmann::json> mRecords;
  std::set<std::string> mKeys;
};

}  // namespace canopy
