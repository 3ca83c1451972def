#include "common/config.h"

#include <gtest/gtest.h>

#include "bench/experiment.h"

namespace canopy {
namespace {

using nlohmann::json;

std::string errorOf(const json& config) {
  try {
    parseExperimentConfig(config, "");
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(Config, UnknownKeysAreErrorsNamingTheKey) {
  EXPECT_NE(errorOf({{"name", "x"}, {"method", "polygonal"}}).find("method"), std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"distance", {2}}}}}).find("views.distance"),
            std::string::npos);
  const std::string error = errorOf(
      {{"name", "x"}, {"methods", {{{"method", "polygonal"}, {"params", {{"wod", false}}}}}}});
  EXPECT_NE(error.find("wod"), std::string::npos) << error;
  EXPECT_NE(error.find("polygonal"), std::string::npos) << error;
}

TEST(Config, OutOfRangeAndWrongTypesAreErrors) {
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"supersample", 0}}}}).find("views.supersample"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"distances", {0.5}}}}}).find("views.distances"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"shading", "pbr"}}}}).find("views.shading"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"forests", {{"frames", "ten"}}}}).find("forests.frames"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"methods", {{{"method", "nope"}}}}}).find("nope"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"trees", {{{"preset", "palm"}}}}}).find("palm"),
            std::string::npos);
  EXPECT_NE(errorOf(json::object()).find("name"), std::string::npos);
}

// The message of parseJson on `text`, or "" when it parsed.
std::string jsonErrorOf(const std::string& text) {
  try {
    parseJson(text, "in.json");
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(Json, HostileTextIsAnErrorNamingTheSourceNotACrash) {
  const std::string deep(100000, '[');
  EXPECT_NE(jsonErrorOf(R"({"name": "x", "k": )" + deep + std::string(100000, ']') + "}")
                .find("in.json: not valid JSON (nested deeper than 64 levels)"),
            std::string::npos);
  EXPECT_NE(jsonErrorOf(R"({"name": )" + deep).find("in.json"), std::string::npos);
  EXPECT_NE(
      jsonErrorOf(R"({"name": "a", "views": {}, "name": "b"})").find("\"name\" appears twice"),
      std::string::npos);
  // The same key in two different objects is fine, in nested and sibling objects alike.
  EXPECT_EQ(jsonErrorOf(R"({"a": {"a": 1, "b": {"a": 2}}, "b": [{"a": 1}, {"a": 2}]})"), "");
  EXPECT_NE(jsonErrorOf(R"({"fov_deg": 1e400})").find("in.json: not valid JSON"),
            std::string::npos);
  const std::string message = jsonErrorOf(R"({"a": tru})");
  EXPECT_EQ(message.find("[json.exception"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  // 64 levels still parse: real files nest a handful.
  EXPECT_EQ(jsonErrorOf(std::string(64, '[') + std::string(64, ']')), "");
  EXPECT_NE(jsonErrorOf(std::string(65, '[') + std::string(65, ']')), "");
}

TEST(Config, NamesThatArePathComponentsCannotEscapeTheirFolder) {
  for (const std::string& name :
       std::vector<std::string>{".", "..", "", "a/b", "../up", std::string(30000, 'a')}) {
    const std::string error = errorOf({{"name", name}});
    EXPECT_NE(error.find("config name"), std::string::npos) << name.substr(0, 20) << ": " << error;
    EXPECT_LT(error.size(), 300u) << "a long name is shortened in the message";
  }
  EXPECT_EQ(errorOf({{"name", "run-1.b_2"}}), "");
  const std::string tree =
      errorOf({{"name", "x"}, {"trees", {{{"preset", "sparse"}, {"name", ".."}}}}});
  EXPECT_NE(tree.find("trees[0].name"), std::string::npos) << tree;
}

TEST(Config, EmptyListsThatWouldRunNothingAreErrors) {
  EXPECT_NE(errorOf({{"name", "x"}, {"trees", json::array()}}).find("config trees"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"methods", json::array()}}).find("config methods"),
            std::string::npos);
  for (const char* list : {"distances", "elevations"}) {
    EXPECT_NE(errorOf({{"name", "x"}, {"views", {{list, json::array()}}}}).find(list),
              std::string::npos);
  }
  EXPECT_NE(errorOf({{"name", "x"}, {"forests", {{"sizes", json::array()}}}}).find("forests.sizes"),
            std::string::npos);
}

TEST(Config, FairHarnessSettingsAreCheckedAndNamed) {
  EXPECT_NE(
      errorOf({{"name", "x"}, {"views", {{"closeups", {{"fov", 8}}}}}}).find("views.closeups.fov"),
      std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"closeups", {{"fov_deg", 0.1}}}}}})
                .find("views.closeups.fov_deg"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"flip_ppd", 0}}}}).find("views.flip_ppd"),
            std::string::npos);
  EXPECT_NE(errorOf({{"name", "x"}, {"views", {{"ambient_occlusion", 1}}}})
                .find("views.ambient_occlusion"),
            std::string::npos);
  EXPECT_NE(
      errorOf({{"name", "x"}, {"forests", {{"frames", 4}, {"blocks", 5}}}}).find("forests.blocks"),
      std::string::npos);
  const ExperimentConfig config = parseExperimentConfig(
      {{"name", "c"},
       {"views",
        {{"flip_ppd", 40},
         {"ambient_occlusion", false},
         {"closeups", {{"distance", 2}, {"fov_deg", 6}, {"azimuths", 3}, {"elevations", {10}}}}}},
       {"forests", {{"frames", 3}}}},
      "");
  EXPECT_TRUE(config.views.closeups.enabled);
  EXPECT_FLOAT_EQ(config.views.closeups.fovYDegrees, 6.0f);
  EXPECT_EQ(config.views.closeups.azimuths, 3);
  EXPECT_DOUBLE_EQ(config.views.render.flipPixelsPerDegree, 40.0);
  EXPECT_FALSE(config.views.render.ambientOcclusion);
  EXPECT_EQ(config.forests.timing.blocks, 3) << "without blocks: as many as the frames allow";
  EXPECT_FALSE(parseExperimentConfig({{"name", "d"}}, "").views.closeups.enabled);
}

// Large forests are timed on their own shorter path; smaller ones keep the config's timing.
TEST(Config, LargeForestsTimeFewerFrames) {
  const ExperimentConfig config = parseExperimentConfig({{"name", "f"},
                                                         {"forests",
                                                          {{"sizes", {100, 10000}},
                                                           {"frames", 10},
                                                           {"warmup", 2},
                                                           {"blocks", 5},
                                                           {"large_from", 5000},
                                                           {"large_frames", 3},
                                                           {"large_warmup", 0}}}},
                                                        "");
  const ForestTiming small = config.forests.timingFor(100), large = config.forests.timingFor(10000);
  EXPECT_EQ(small.frames, 10);
  EXPECT_EQ(small.warmup, 2);
  EXPECT_EQ(small.blocks, 5);
  EXPECT_EQ(large.frames, 3);
  EXPECT_EQ(large.warmup, 0);
  EXPECT_EQ(large.blocks, 1);
  EXPECT_EQ(large.width, small.width);
  const ExperimentConfig none =
      parseExperimentConfig({{"name", "g"}, {"forests", {{"sizes", {10000}}}}}, "");
  EXPECT_EQ(none.forests.timingFor(10000).frames, none.forests.timing.frames) << "large_from 0";
}

TEST(Config, ListsInParamsAreSweeps) {
  const auto points = expandSweep({{"a", {1, 2}}, {"b", {"x", "y", "z"}}, {"c", 5}});
  ASSERT_EQ(points.size(), 6u);
  EXPECT_EQ(points[0], json({{"a", 1}, {"b", "x"}, {"c", 5}}));
  EXPECT_EQ(points[5], json({{"a", 2}, {"b", "z"}, {"c", 5}}));
  const ExperimentConfig config = parseExperimentConfig(
      {{"name", "s"},
       {"methods", {{{"method", "polygonal"}, {"params", {{"wood", {true, false}}}}}}}},
      "");
  ASSERT_EQ(config.variants.size(), 2u);
  EXPECT_EQ(config.variants[0].label, "polygonal[wood=true]");
  EXPECT_EQ(config.variants[1].label, "polygonal[wood=false]");
}

TEST(Config, DefaultsAreDesignDefaults) {
  const ExperimentConfig config = parseExperimentConfig({{"name", "d"}}, "");
  EXPECT_EQ(config.views.render.supersample, 2);
  EXPECT_EQ(config.views.render.width, 512);
  EXPECT_EQ(config.views.elevations, (std::vector<float>{0, 30, 60, 90}));
  EXPECT_EQ(config.trees.size(), 1u);
  EXPECT_FALSE(config.variants.empty());
  EXPECT_EQ(config.hash, hashJson({{"name", "d"}}));
}

}  // namespace
}  // namespace canopy

namespace canopy {
namespace {

// Every committed config parses and validates (names, keys, ranges, method parameters), so a
// researcher running one never loses a long run to a typo found at the end.
TEST(Config, EveryCommittedConfigParses) {
  int configs = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(CANOPY_SOURCE_DIR) / "configs")) {
    if (entry.path().extension() != ".json") continue;
    ++configs;
    EXPECT_NO_THROW({
      const ExperimentConfig config = readExperimentConfig(entry.path().string());
      EXPECT_EQ(config.name, entry.path().stem().string()) << "results/<name> matches the file";
    }) << entry.path();
  }
  EXPECT_GE(configs, 10);
}

}  // namespace
}  // namespace canopy
