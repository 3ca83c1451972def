#include "bench/merge.h"

#include <set>
#include <string>

#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "bench/report.h"
#include "bench/results_store.h"
#include "bench/run_meta.h"
#include "common/atomic_file.h"
#include "common/config.h"
#include "common/error.h"
#include "common/system_info.h"

namespace canopy {

void mergeRuns(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out) {
  if (inputs.empty()) throwInputError("merge: name at least one run folder to merge");
  std::vector<Record> records;
  std::set<std::string> keys;
  nlohmann::json sources = nlohmann::json::array();
  std::set<std::string> renderers, hashes;
  std::string title;
  for (const auto& input : inputs) {
    const auto metrics = input / "metrics.jsonl", metaPath = input / "meta.json";
    if (!std::filesystem::is_regular_file(metrics) || !std::filesystem::is_regular_file(metaPath)) {
      throwInputError("{}: not a canopy-bench run (needs metrics.jsonl and meta.json)",
                      input.string());
    }
    const RunMeta meta = readRunMeta(input);
    if (title.empty()) title = meta.experiment;
    renderers.insert(meta.gl.renderer);
    hashes.insert(meta.configHash ? *meta.configHash : "");
    sources.push_back({{"folder", input.string()}, {"meta", readJsonFile(metaPath.string())}});
    size_t duplicates = 0;
    for (Record& record : ResultsStore::readRecords(metrics)) {
      const std::string& key = recordKeyOf(record);
      if (key.empty()) throwInputError("{}: a record has an empty record_key", metrics.string());
      if (!keys.insert(key).second) {
        ++duplicates;
        continue;
      }
      records.push_back(std::move(record));
    }
    if (duplicates > 0)
      spdlog::info("{}: {} records already present, kept the first", input.string(), duplicates);
  }
  if (hashes.size() > 1)
    spdlog::warn("merge: the runs come from {} different configs", hashes.size());
  std::string renderer;
  for (const std::string& r : renderers) renderer += (renderer.empty() ? "" : " + ") + r;
  if (renderers.size() > 1) spdlog::warn("merge: the runs used different renderers: {}", renderer);
  std::filesystem::create_directories(out);
  std::string lines;
  for (const Record& record : records) lines += recordToJson(record).dump() + "\n";
  writeTextAtomically(out / "metrics.jsonl", lines);
  writeSummaries(out, records, title, renderer);
  writeTextAtomically(out / "meta.json", nlohmann::json({{"experiment", title},
                                                         {"merged", isoTimestampUtc()},
                                                         {"git_commit", gitCommit()},
                                                         {"gl", {{"renderer", renderer}}},
                                                         {"sources", sources}})
                                             .dump(2));
  spdlog::info("merged {} records from {} runs into {}", records.size(), inputs.size(),
               out.string());
}

}  // namespace canopy
