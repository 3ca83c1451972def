// Runs that are what they say: a folder's records come from one config and one code version, one
// process writes a folder at a time, and every record carries the fair-harness fields.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <set>

#include "bench/results_store.h"
#include "bench/run_folder.h"
#include "common/config.h"
#include "test_support.h"

namespace canopy {
namespace {

const std::string kBench = CANOPY_BENCH_EXE;

std::string config(int resolution, bool closeups = false) {
  return R"({"name": "rf", "trees": [{"preset": "sparse", "seed": 3, "leaves": 200}],
    "methods": [{"method": "polygonal"}, {"method": "billboard_cloud", "params": {"clusters": 20}}],
    "views": {"resolution": [)" +
         std::to_string(resolution) + ", " + std::to_string(resolution) +
         R"(], "distances": [3], "elevations": [30], "azimuths": 2)" +
         (closeups
              ? R"(, "closeups": {"distance": 1.5, "fov_deg": 8, "azimuths": 2, "elevations": [0]})"
              : "") +
         R"(}, "forests": {"sizes": [2], "frames": 4, "warmup": 1, "blocks": 2}})";
}

std::vector<nlohmann::json> recordsOf(const std::filesystem::path& run) {
  return test::readJsonRecords(run / "metrics.jsonl");
}

std::vector<std::filesystem::path> previousRuns(const test::TempDir& dir) {
  std::vector<std::filesystem::path> found;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    if (entry.path().filename().string().rfind("out.previous-", 0) == 0)
      found.push_back(entry.path());
  return found;
}

class RunFolderCli : public testing::Test {
 protected:
  int run(int resolution, const std::string& flags = "", std::string* error = nullptr,
          bool closeups = false) {
    test::writeText(mDir / "c.json", config(resolution, closeups));
    return test::runCommand(kBench + " --quiet --no-images " + flags + " --config " +
                                (mDir / "c.json").string() + " --out " + out().string(),
                            error);
  }
  std::filesystem::path out() const { return mDir / "out"; }
  test::TempDir mDir;
};

TEST_F(RunFolderCli, AChangedConfigIsRefusedAndFreshMovesTheOldRunAside) {
  ASSERT_EQ(run(48), 0);
  const auto before = recordsOf(out());
  std::string error;
  EXPECT_EQ(run(32, "", &error), 2);
  EXPECT_NE(error.find(out().string()), std::string::npos) << error;
  EXPECT_NE(error.find("--fresh"), std::string::npos) << error;
  EXPECT_EQ(std::count(error.begin(), error.end(), '\n'), 1) << error;
  EXPECT_EQ(recordsOf(out()).size(), before.size()) << "nothing written";
  // --fresh: the old run is kept aside whole, the folder holds only the new config's records.
  ASSERT_EQ(run(32, "--fresh"), 0);
  const auto aside = previousRuns(mDir);
  ASSERT_EQ(aside.size(), 1u);
  EXPECT_EQ(recordsOf(aside[0]).size(), before.size());
  for (const auto& record : recordsOf(out())) {
    if (record.at("kind") == "view") {
      EXPECT_EQ(record.at("resolution")[0], 32);
    }
  }
  const auto meta = readJsonFile((out() / "meta.json").string());
  EXPECT_EQ(meta.at("config").at("views").at("resolution")[0], 32);
  EXPECT_FALSE(meta.at("code_version").get<std::string>().empty());
}

TEST_F(RunFolderCli, ResumeOrFreshResumesAnUnfinishedRunAndRedoesAFinishedOne) {
  ASSERT_EQ(run(48), 0);
  const size_t complete = recordsOf(out()).size();
  // An interrupted run: its meta.json is the one written at its start (no "finished", no part
  // of its own in "runs") and some records are missing.
  nlohmann::json meta = readJsonFile((out() / "meta.json").string());
  meta.erase("finished");
  meta["runs"] = nlohmann::json::array();
  test::writeText(out() / "meta.json", meta.dump());
  const auto records = recordsOf(out());
  std::string partial;
  for (size_t i = 0; i + 3 < records.size(); ++i) partial += records[i].dump() + "\n";
  test::writeText(out() / "metrics.jsonl", partial);
  ASSERT_EQ(run(48, "--resume-or-fresh"), 0);
  EXPECT_TRUE(previousRuns(mDir).empty()) << "resumed in place";
  EXPECT_EQ(recordsOf(out()).size(), complete);
  // The folder says it ran in two parts: the interrupted start, then the part that finished.
  const auto runs = readJsonFile((out() / "meta.json").string()).at("runs");
  ASSERT_EQ(runs.size(), 2u) << runs.dump();
  EXPECT_EQ(runs[0].at("started"), meta.at("started"));
  EXPECT_TRUE(runs[0].at("finished").is_null());
  EXPECT_TRUE(runs[0].at("interrupted").get<bool>());
  EXPECT_FALSE(runs[1].at("finished").is_null());
  // A finished run is done again (the committed-results case of `make bench`).
  ASSERT_EQ(run(48, "--resume-or-fresh"), 0);
  EXPECT_EQ(previousRuns(mDir).size(), 1u);
  EXPECT_EQ(recordsOf(out()).size(), complete);
}

TEST_F(RunFolderCli, ASecondProcessCannotWriteTheSameFolder) {
  std::filesystem::create_directories(out());
  {
    const RunFolder held(out(), {"hash", "code"}, ResumePolicy::kResume);
    std::string error;
    EXPECT_EQ(run(32, "", &error), 2);
    EXPECT_NE(error.find("another canopy-bench run"), std::string::npos) << error;
    EXPECT_NE(error.find(std::to_string(::getpid())), std::string::npos) << error;
  }
  EXPECT_EQ(run(32), 0) << "the lock is released with its holder";
}

TEST(RunFolder, TheLockDiesWithAKilledProcess) {
  test::TempDir dir;
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const RunFolder held(dir / "out", {"h", "c"}, ResumePolicy::kResume);
    [[maybe_unused]] const ssize_t n = ::write(ready[1], "x", 1);
    ::pause();
    ::_exit(0);
  }
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  EXPECT_THROW(RunFolder(dir / "out", {"h", "c"}, ResumePolicy::kResume), InputError);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  EXPECT_NO_THROW(RunFolder(dir / "out", {"h", "c"}, ResumePolicy::kResume));
  ::close(ready[0]);
  ::close(ready[1]);
}

TEST_F(RunFolderCli, RecordsSayWhatWasDrawnAndHowItScored) {
  ASSERT_EQ(run(48, "", nullptr, true), 0);
  int closeups = 0, orbit = 0, forests = 0;
  for (const auto& record : recordsOf(out())) {
    const std::string kind = record.at("kind");
    if (kind == "view") {
      for (const char* key : {"fov_deg", "ring", "flip", "drawn", "supersample", "resolution"})
        EXPECT_TRUE(record.contains(key)) << key;
      const auto& drawn = record.at("drawn");
      EXPECT_GT(drawn.at("primitives").get<double>(), 0.0);
      EXPECT_GT(drawn.at("fragments").get<double>(), 0.0);
      const double leaves = drawn.at("leaf_geometry_fraction");
      if (record.at("method") == "polygonal") {
        EXPECT_DOUBLE_EQ(leaves, 1.0);
        EXPECT_DOUBLE_EQ(record.at("flip").get<double>(), 0.0);
      } else {
        EXPECT_DOUBLE_EQ(leaves, 0.0) << "a pure impostor draws no leaf polygons";
        EXPECT_GT(record.at("flip").get<double>(), 0.0);
      }
      if (record.at("ring") == "closeup") {
        ++closeups;
        EXPECT_DOUBLE_EQ(record.at("fov_deg").get<double>(), 8.0);
      } else {
        ++orbit;
        EXPECT_EQ(record.at("ring"), "orbit");
        EXPECT_DOUBLE_EQ(record.at("fov_deg").get<double>(), 40.0);
      }
    } else if (kind == "forest") {
      ++forests;
      for (const char* key : {"drawn", "speedup_spread", "psnr", "flip", "coverage_error",
                              "block_speedups", "frame_speedups", "reference_coverage"})
        EXPECT_TRUE(record.contains(key)) << key;
      const auto& spread = record.at("speedup_spread");
      EXPECT_LE(spread[0].get<double>(), spread[1].get<double>());
      // The speedup is the geometric mean of the per-camera ratios the record keeps.
      double logSum = 0.0;
      for (const auto& ratio : record.at("frame_speedups")) logSum += std::log(ratio.get<double>());
      EXPECT_NEAR(record.at("speedup_vs_polygonal").get<double>(),
                  std::exp(logSum / double(record.at("frame_speedups").size())), 1e-9);
      EXPECT_GT(record.at("reference_coverage").get<double>(), 0.0);
      EXPECT_EQ(record.at("block_speedups").size(), 2u);
      EXPECT_EQ(record.at("frame_speedups").size(), record.at("frames").get<size_t>());
    }
  }
  EXPECT_EQ(closeups, 2 * 2);
  EXPECT_EQ(orbit, 2 * 2);
  EXPECT_EQ(forests, 2);
  const std::string summary = test::readText(out() / "summary.md");
  EXPECT_NE(summary.find("PSNR close-up"), std::string::npos);
  EXPECT_NE(summary.find("## What was drawn"), std::string::npos);
  const auto meta = readJsonFile((out() / "meta.json").string());
  EXPECT_FALSE(meta.at("draw_statistics").get<std::string>().empty());
}

}  // namespace
}  // namespace canopy
