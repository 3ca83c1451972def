#pragma once

#include <string>
#include <vector>

namespace canopy {

struct ProcessResult {
  int exitCode = -1;   // the program's exit status; 127 when it could not be started
  std::string output;  // what it wrote to stdout
  std::string errors;  // what it wrote to stderr
};

// Runs `argv[0]` (looked up on PATH) with `argv` and no shell, waits for it and collects its
// stdout and stderr.
ProcessResult runProcess(const std::vector<std::string>& argv);

}  // namespace canopy
