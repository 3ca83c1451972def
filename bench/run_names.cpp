#include "bench/run_names.h"

#include <regex>

#include <nlohmann/json.hpp>

#include "bench/report.h"
#include "common/atomic_file.h"

namespace canopy {

std::string safeName(const std::string& label) {
  return std::regex_replace(label, std::regex("[^A-Za-z0-9_.=,-]"), "_");
}

void writeRunNames(const std::filesystem::path& directory, const std::vector<SummaryRow>& rows) {
  nlohmann::json trees = nlohmann::json::object(), variants = nlohmann::json::object();
  for (const SummaryRow& row : rows) {
    trees[row.tree] = safeName(row.tree);
    variants[row.variant] = safeName(row.variant);
  }
  variants["reference"] = "reference";
  writeTextAtomically(directory / "names.json",
                      nlohmann::json({{"trees", trees}, {"variants", variants}}).dump(2) + "\n");
}

}  // namespace canopy
