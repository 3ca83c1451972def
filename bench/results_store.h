#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/records.h"

namespace canopy {

// results/<experiment>/metrics.jsonl: one JSON record per line (bench/records.h), appended
// durably. On open, a torn last line (a run killed mid-write) is cut off, so the file holds only
// whole records, and the keys of the records present let a resumed run skip what is done.
class ResultsStore {
 public:
  explicit ResultsStore(std::filesystem::path directory);

  const std::filesystem::path& directory() const { return mDirectory; }
  std::filesystem::path metricsPath() const { return mDirectory / "metrics.jsonl"; }
  bool has(const std::string& key) const { return mIndex.contains(key); }
  // The record appended under `key`, or nullptr.
  const Record* find(const std::string& key) const;
  // Sets the record's record_key and appends it.
  void append(Record record, const std::string& key);
  const std::vector<Record>& records() const { return mRecords; }

  // Reads a metrics.jsonl (whole lines only), every record checked against the schema; an
  // InputError names the file and line of the first bad one.
  static std::vector<Record> readRecords(const std::filesystem::path& path);

 private:
  std::filesystem::path mDirectory;
  std::vector<Record> mRecords;
  std::map<std::string, size_t> mIndex;  // record_key → position in mRecords
};

}  // namespace canopy
