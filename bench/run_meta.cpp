#include "bench/run_meta.h"

#include "common/config.h"

namespace canopy {

RunMeta readRunMeta(const std::filesystem::path& directory) {
  const std::string path = (directory / "meta.json").string();
  const nlohmann::json json = readJsonFile(path);
  RunMeta meta;
  JsonFieldReader reader(json, path);  // other keys are the runner's own, not read back
  meta.visit(reader);
  return meta;
}

}  // namespace canopy
