#include "bench/results_store.h"

#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/atomic_file.h"
#include "common/config.h"
#include "common/error.h"

namespace canopy {

std::vector<Record> ResultsStore::readRecords(const std::filesystem::path& path) {
  std::vector<Record> records;
  std::ifstream in(path, std::ios::binary);
  if (!in) return records;
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  size_t start = 0, lineNumber = 0;
  for (size_t end = text.find('\n'); end != std::string::npos; end = text.find('\n', start)) {
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    ++lineNumber;
    if (line.empty()) continue;
    const std::string where = fmt::format("{}:{}", path.string(), lineNumber);
    records.push_back(recordFromJson(parseJson(line, where), where));
  }
  return records;
}

ResultsStore::ResultsStore(std::filesystem::path directory) : mDirectory(std::move(directory)) {
  std::filesystem::create_directories(mDirectory);
  const auto path = metricsPath();
  if (std::filesystem::exists(path)) {
    // Cut a torn last line: everything after the last newline.
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    const size_t lastNewline = text.rfind('\n');
    const size_t whole = lastNewline == std::string::npos ? 0 : lastNewline + 1;
    if (whole != text.size()) {
      spdlog::warn("{}: dropping a torn last record ({} bytes) left by an interrupted run",
                   path.string(), text.size() - whole);
      std::filesystem::resize_file(path, whole);
    }
  }
  mRecords = readRecords(path);
  for (size_t i = 0; i < mRecords.size(); ++i) mIndex.emplace(recordKeyOf(mRecords[i]), i);
}

const Record* ResultsStore::find(const std::string& key) const {
  const auto it = mIndex.find(key);
  return it == mIndex.end() ? nullptr : &mRecords[it->second];
}

void ResultsStore::append(Record record, const std::string& key) {
  recordKeyOf(record) = key;
  appendLineDurably(metricsPath(), recordToJson(record).dump());
  mIndex.emplace(key, mRecords.size());
  mRecords.push_back(std::move(record));
}

}  // namespace canopy
