#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "bench/results_store.h"
#include "common/error.h"
#include "common/gl/context.h"
#include "common/lsystem.h"
#include "methods/method.h"

namespace canopy::test {

// A fresh folder under the system temp dir, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "canopy_test_XXXXXX").string();
    mPath = ::mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(mPath, ignored);
  }
  const std::filesystem::path& path() const { return mPath; }
  std::filesystem::path operator/(const std::string& name) const { return mPath / name; }

 private:
  std::filesystem::path mPath;
};

inline void writeText(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A small built-in tree so tests stay fast: the sparse preset with `leaves` leaves.
inline Tree smallTree(int leaves = 400, uint64_t seed = 7) {
  LSystemTreeParams params = treePreset("sparse");
  params.leaves = leaves;
  params.leafTextureSize = 64;
  return generateTree(params, seed);
}

// The headless context the tests render with (OSMesa, as on CI machines without a GPU).
inline std::unique_ptr<gl::Context> makeTestContext() {
  return gl::createContext({gl::Backend::kOsMesa});
}

// A registered method made from `params`, baked from `tree` and uploaded through `device`, its
// GPU memory charged to `owner` (the method's name when empty).
inline std::unique_ptr<Method> bakeAndUpload(gl::Device& device, const Tree& tree,
                                             const std::string& name, const nlohmann::json& params,
                                             Shading shading = Shading::kUnlit,
                                             const std::string& owner = "") {
  auto method = builtinMethods().find(name).create(params, "test");
  BakeContext context;
  context.shading = shading;
  method->bake(tree, context);
  gl::Device::OwnerScope scope(device, owner.empty() ? name : owner);
  method->upload(device);
  return method;
}

// Runs a command; returns its exit code and captures stderr into `errorOutput`.
inline int runCommand(const std::string& command, std::string* errorOutput = nullptr) {
  const std::string errorFile = (std::filesystem::temp_directory_path() /
                                 ("canopy_cmd_" + std::to_string(::getpid()) + ".err"))
                                    .string();
  const int status = std::system((command + " > /dev/null 2> " + errorFile).c_str());
  if (errorOutput) {
    std::ifstream in(errorFile);
    errorOutput->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::filesystem::remove(errorFile);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Runs `command` on a virtual X server (xvfb-run -a) and returns the command's own exit code:
// xvfb-run replaces it with 5 when removing its temporary folder fails after the command ended,
// which happens here now and then and says nothing about the program under test.
inline int runUnderXvfb(const std::string& command, std::string* errorOutput = nullptr) {
  const std::filesystem::path base =
      std::filesystem::temp_directory_path() / ("canopy_xvfb_" + std::to_string(::getpid()));
  const std::string script = base.string() + ".sh", codeFile = base.string() + ".code";
  std::filesystem::remove(codeFile);
  // A script, so the command keeps its own quoting.
  std::ofstream(script) << command << "\necho $? > " << codeFile << "\n";
  const int xvfbCode = runCommand("xvfb-run -a sh " + script, errorOutput);
  std::ifstream in(codeFile);
  int code = xvfbCode;
  if (!(in >> code)) code = xvfbCode;  // the server never started: xvfb-run's own code
  std::filesystem::remove(codeFile);
  std::filesystem::remove(script);
  return code;
}

// A record of fields["kind"] holding `fields` and defaults for the rest, read through the strict
// schema: concise test records of the real format.
inline Record makeRecord(const nlohmann::json& fields) {
  const std::string kind = fields.at("kind");
  nlohmann::json full;
  if (kind == "tree") full = recordToJson(TreeRecord{});
  if (kind == "bake") full = recordToJson(BakeRecord{});
  if (kind == "view") full = recordToJson(ViewRecord{});
  if (kind == "forest") full = recordToJson(ForestRecord{});
  if (kind == "popping") full = recordToJson(PoppingRecord{});
  if (kind == "skip") full = recordToJson(SkipRecord{});
  full.update(fields);
  return recordFromJson(full, "test record");
}

inline std::vector<Record> makeRecords(const std::vector<nlohmann::json>& fields) {
  std::vector<Record> records;
  for (const nlohmann::json& f : fields) records.push_back(makeRecord(f));
  return records;
}

// The records of a metrics.jsonl (read through the schema) as JSON objects.
inline std::vector<nlohmann::json> readJsonRecords(const std::filesystem::path& path) {
  std::vector<nlohmann::json> records;
  for (const Record& record : ResultsStore::readRecords(path))
    records.push_back(recordToJson(record));
  return records;
}

// Each (key, value) given alone to `method` must be an InputError whose message names the key.
inline void expectParameterErrorsNameTheKey(
    const std::string& method, const std::vector<std::pair<std::string, nlohmann::json>>& cases);

}  // namespace canopy::test

#include "methods/method.h"

namespace canopy::test {

inline void expectParameterErrorsNameTheKey(
    const std::string& method, const std::vector<std::pair<std::string, nlohmann::json>>& cases) {
  const auto& create = builtinMethods().find(method).create;
  for (const auto& [key, value] : cases) {
    try {
      create({{key, value}}, "test");
      ADD_FAILURE() << method << ": " << key << " = " << value.dump() << " was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(key), std::string::npos) << error.what();
    }
  }
}

// Loading the asset in `folder` into `method` must be an InputError naming the folder (a corrupt
// or truncated asset); `what` names the corruption in failure messages.
inline void expectLoadErrorNamesTheFolder(Method& method, const std::filesystem::path& folder,
                                          const std::string& what) {
  AssetFolder reader(folder);
  try {
    method.load(reader);
    ADD_FAILURE() << what << " was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(folder.string()), std::string::npos)
        << what << ": " << error.what();
  }
}

}  // namespace canopy::test
