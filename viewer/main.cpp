// canopy-view: fly through a forest, switch methods and parameters live, compare with the
// reference. Exit codes: 0 success, 2 bad input (one line on stderr), 1 internal error.
#include <cstdio>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "common/command_line.h"
#include "common/config.h"
#include "common/error.h"
#include "viewer/viewer.h"

int main(int argc, char** argv) {
  using namespace canopy;
  CLI::App app{"canopy-view: interactive viewer for Canopy's tree impostor methods"};
  ViewerOptions options;
  std::string params;
  app.add_option("--config", options.config, "experiment config: its trees and method variants");
  app.add_option("--tree", options.tree, "preset (broadleaf | shrub | sparse) or a tree file");
  app.add_option("--leaves", options.leaves, "preset leaf count (0: the preset's)")
      ->check(CLI::Range(0, 2'000'000));
  app.add_option("--method", options.method, "method to show first");
  app.add_option("--params", params, "the method's parameters as a JSON object");
  app.add_option("--width", options.width, "window width");
  app.add_option("--height", options.height, "window height");
  app.add_option("--forest", options.forest, "trees in the forest");
  app.add_option("--screenshot", options.screenshot, "render --frames frames, save PNG, exit");
  app.add_option("--frames", options.frames, "frames before the scripted screenshot");
  app.add_flag("--hide-ui", options.hideUi, "no ImGui panel");
  app.add_flag("--lit", options.lit, "lit shading (two-sided Lambert)");
  app.add_flag("--shadows", options.shadows, "lit shading with shadow maps");
  app.add_option("--view", options.view, "method | split | error (reference vs method)")
      ->check(CLI::IsMember({"method", "split", "error"}));
  app.add_option("--bookmarks", options.bookmarks, "camera bookmarks file (JSON)");
  app.add_option("--camera-path", options.cameraPath, "where a recorded camera path is saved");
  if (const auto exitCode = parseCommandLine(app, "canopy-view", argc, argv)) return *exitCode;
  return runWithExitCodes("canopy-view", [&]() -> int {
    if (!params.empty()) {
      options.params = parseJson(params, "--params");
      if (!options.params.is_object()) throwInputError("--params: expected a JSON object");
    }
    if (options.width < 64 || options.height < 64 || options.width > 8192 || options.height > 8192)
      throwInputError("--width/--height: out of range [64, 8192]");
    if (options.forest < 1 || options.forest > 100000)
      throwInputError("--forest: out of range [1, 100000]");
    if (options.frames < 1) throwInputError("--frames: must be >= 1");
    runViewer(options);
    return kExitOk;
  });
}
