#include "bench/results_store.h"

#include <fstream>
#include <sstream>

#include <spdlog/spdlog.h>

#include "common/atomic_file.h"
#include "common/error.h"

namespace canopy {

std::vector<nlohmann::json> ResultsStore::readRecords(const std::filesystem::path& path) {
  std::vector<nlohmann::json> records;
  std::ifstream in(path, std::ios::binary);
  if (!in) return records;
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  size_t start = 0;
  for (size_t end = text.find('\n'); end != std::string::npos; end = text.find('\n', start)) {
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    if (line.empty()) continue;
    try {
      records.push_back(nlohmann::json::parse(line));
    } catch (const nlohmann::json::parse_error& error) {
      throwInputError("{}: line {} is not a JSON record ({})", path.string(), records.size() + 1,
                      error.what());
    }
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
  for (const nlohmann::json& record : mRecords) {
    if (record.contains("record_key")) mKeys.insert(record["record_key"].get<std::string>());
  }
}

const nlohmann::json* ResultsStore::find(const std::string& key) const {
  if (!has(key)) return nullptr;
  for (const nlohmann::json& record : mRecords)
    if (record.value("record_key", "") == key) return &record;
  return nullptr;
}

void ResultsStore::append(nlohmann::json record, const std::string& key) {
  record["record_key"] = key;
  appendLineDurably(metricsPath(), record.dump());
  mKeys.insert(key);
  mRecords.push_back(std::move(record));
}

}  // namespace canopy
