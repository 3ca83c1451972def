#pragma once

#include <optional>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "common/error.h"

namespace canopy {

// Parses a command line under the exit-code contract: --help prints the usage and ends with 0, a
// bad option is one line "<program>: <what CLI11 says> (see --help)" and 2. Returns the code to
// exit with, or nothing when the program should go on.
inline std::optional<int> parseCommandLine(CLI::App& app, const std::string& program, int argc,
                                           char** argv) {
  app.failure_message([program](const CLI::App*, const CLI::Error& error) {
    return fmt::format("{}: {} (see --help)\n", program, error.what());
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? kExitOk : kExitBadInput;
  }
  return std::nullopt;
}

}  // namespace canopy
