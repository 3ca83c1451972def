// One record schema (bench/records.h): what the runner writes, report, merge and resume read back
// through the same field lists, strictly; and every committed run is read through it.
#include <gtest/gtest.h>

#include <filesystem>

#include "bench/records.h"
#include "bench/report.h"
#include "bench/results_store.h"
#include "bench/run_meta.h"
#include "test_support.h"

namespace canopy {
namespace {

ViewRecord sampleView() {
  ViewRecord v;
  v.tree = "oak";
  v.method = "m";
  v.variant = "m[a=1]";
  v.params = {{"a", 1}};
  v.ring = "orbit";
  v.fovDegrees = 40.0;
  v.distance = 1.5;
  v.elevation = 30.0;
  v.azimuth = 90.0;
  v.psnr = 20.5;
  v.psnrFrame = 31.0;
  v.ssim = 0.7;
  v.flip = 0.12;
  v.coverageError = 0.05;
  v.unionPixels = 1234;
  v.resolution = {64, 48};
  v.supersample = 2;
  v.drawn = {100, 5000, 0.25};
  v.shading = "unlit";
  v.recordKey = "oak|m[a=1]|view|d1.5_e30_a90";
  return v;
}

TEST(Records, EveryKindRoundTripsThroughJson) {
  BakeRecord bake;
  bake.tree = "oak";
  bake.method = bake.variant = "polygonal";
  bake.memory = {1, 2, 3, 6};
  bake.diskBytes = 99;
  BudgetRecord budget;
  budget.mode = "memory_mb";
  budget.value = 16;
  budget.trace = {{8, 1.5, 1.5}};
  bake.budget = budget;
  ForestRecord forest;
  forest.speedupSpread = std::array<double, 2>{1.0, 2.0};
  forest.blockSpeedups = std::vector<double>{1.0, 1.5, 2.0};
  forest.frameSpeedups = std::vector<double>{0.9, 1.1, 1.5, 1.6, 2.0, 2.1};
  PoppingRecord popping;
  popping.distance = {1.5, 3.0};
  popping.lodSwitch = {false, true};
  for (const Record& record :
       std::vector<Record>{TreeRecord{}, bake, sampleView(), forest, popping, SkipRecord{}}) {
    const nlohmann::json json = recordToJson(record);
    EXPECT_EQ(json.at("kind"), kindOf(record));
    EXPECT_EQ(recordToJson(recordFromJson(json, "test")), json) << json.dump();
  }
  // Keys DESIGN.md names, as outside scripts read them.
  const nlohmann::json view = recordToJson(sampleView());
  for (const char* key :
       {"tree", "method", "params", "kind", "distance", "elevation", "azimuth", "psnr",
        "psnr_frame", "ssim", "coverage_error", "fov_deg", "flip", "drawn", "ring"})
    EXPECT_TRUE(view.contains(key)) << key;
  EXPECT_TRUE(view.at("drawn").contains("leaf_geometry_fraction"));
}

TEST(Records, UnknownMissingOrMistypedKeysNameTheFileAndLine) {
  test::TempDir dir;
  nlohmann::json good = recordToJson(sampleView());
  const auto expectError = [&](const nlohmann::json& bad, const std::string& words) {
    test::writeText(dir / "metrics.jsonl", good.dump() + "\n" + bad.dump() + "\n");
    try {
      ResultsStore::readRecords(dir / "metrics.jsonl");
      ADD_FAILURE() << bad.dump() << " was accepted";
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("metrics.jsonl:2"), std::string::npos) << message;
      EXPECT_NE(message.find(words), std::string::npos) << message;
    }
  };
  nlohmann::json renamed = good;
  renamed["psnr_db"] = renamed["psnr"];
  renamed.erase("psnr");
  expectError(renamed, "'psnr'");
  nlohmann::json extra = good;
  extra["surprise"] = 1;
  expectError(extra, "'surprise'");
  nlohmann::json mistyped = good;
  mistyped["union_pixels"] = "many";
  expectError(mistyped, "union_pixels");
  nlohmann::json kind = good;
  kind["kind"] = "viewing";
  expectError(kind, "viewing");
  // Null numbers read as "not measured"; absent optional keys are allowed.
  nlohmann::json capture = good;
  capture.erase("elevation");
  capture.erase("azimuth");
  capture["ssim"] = nullptr;
  test::writeText(dir / "metrics.jsonl", capture.dump() + "\n");
  const auto records = ResultsStore::readRecords(dir / "metrics.jsonl");
  const ViewRecord* view = recordAs<ViewRecord>(records.at(0));
  ASSERT_NE(view, nullptr);
  EXPECT_FALSE(view->elevation);
  EXPECT_TRUE(std::isnan(view->ssim));
}

// Every committed run reads back through the schema, and its summaries are what the report
// writes from its records: a key renamed in the schema fails here, not in a table column.
TEST(Records, CommittedRunsReadBackAndTheirSummariesRegenerateExactly) {
  const std::filesystem::path results = std::filesystem::path(CANOPY_SOURCE_DIR) / "results";
  int runs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(results)) {
    const auto folder = entry.path();
    if (!std::filesystem::exists(folder / "metrics.jsonl")) continue;
    if (folder.filename().string().find(".previous-") != std::string::npos) continue;
    ++runs;
    const std::vector<Record> records = ResultsStore::readRecords(folder / "metrics.jsonl");
    ASSERT_FALSE(records.empty()) << folder;
    const RunMeta meta = readRunMeta(folder);
    const auto rows = summarize(records);
    EXPECT_EQ(formatSummaryCsv(rows), test::readText(folder / "summary.csv")) << folder;
    EXPECT_EQ(formatSummaryMarkdown(rows, meta.experiment, meta.gl.renderer),
              test::readText(folder / "summary.md"))
        << folder;
    EXPECT_EQ(formatSummaryLatex(rows, meta.experiment, meta.gl.renderer),
              test::readText(folder / "summary.tex"))
        << folder;
    const std::string popping = formatPoppingCsv(rows);
    if (!popping.empty()) {
      EXPECT_EQ(popping, test::readText(folder / "popping.csv")) << folder;
    }
  }
  EXPECT_GE(runs, 10) << "the committed runs under " << results;
}

}  // namespace
}  // namespace canopy
