#pragma once

#include <filesystem>
#include <vector>

namespace canopy {

// Joins the outputs of shard runs (or any runs of one config) into `out`: the union of their
// records by record_key (a key seen twice keeps its first record), rewritten atomically, with
// meta.json listing the sources and fresh summaries. InputError naming a folder that is not a
// run (no metrics.jsonl or meta.json).
void mergeRuns(const std::vector<std::filesystem::path>& inputs, const std::filesystem::path& out);

}  // namespace canopy
