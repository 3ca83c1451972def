// Replays every committed fuzz input — the seed corpus and each input that once found a bug —
// through its target in the ordinary build, so a fixed bug stays fixed without running libFuzzer.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fuzz_targets.h"

namespace canopy::fuzz {
namespace {

std::vector<std::filesystem::path> inputsOf(const std::string& target) {
  std::vector<std::filesystem::path> inputs;
  for (const char* kind : {"corpus", "regressions"}) {
    const auto folder = std::filesystem::path(CANOPY_SOURCE_DIR) / "tests" / "fuzz" / kind / target;
    if (!std::filesystem::is_directory(folder)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(folder))
      if (entry.is_regular_file()) inputs.push_back(entry.path());
  }
  std::sort(inputs.begin(), inputs.end());
  return inputs;
}

}  // namespace

// gtest prints a target by its name.
void PrintTo(const Target& target, std::ostream* out) {
  *out << target.name;
}

namespace {

class FuzzReplay : public ::testing::TestWithParam<Target> {};

TEST_P(FuzzReplay, EveryCommittedInputIsHandledWithoutABug) {
  const Target& target = GetParam();
  const auto inputs = inputsOf(target.name);
  EXPECT_GE(inputs.size(), 3u) << "a seed corpus of a few inputs for " << target.name;
  for (const auto& input : inputs) {
    std::ifstream in(input, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(input.string());
    // Anything but an InputError escapes the target and fails here.
    EXPECT_NO_THROW(target.run(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplay, ::testing::ValuesIn(targets()),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace canopy::fuzz
