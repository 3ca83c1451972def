#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/json_fields.h"

namespace canopy {

// The fields of a run folder's meta.json that canopy-bench reads back (report, merge, resume);
// the runner writes more (the config, the CPU, ...). A merged folder's meta has the same
// "experiment" and "gl.renderer".
struct RunMeta {
  struct Gl {
    Absent<std::string> backend, version, vendor;
    std::string renderer;
    template <class V>
    void visit(V& v) {
      v("backend", backend);
      v("renderer", renderer);
      v("version", version);
      v("vendor", vendor);
    }
  };
  std::string experiment;
  Absent<std::string> configHash, codeVersion, started, finished;
  Absent<std::string> shard;  // "I/N" of a shard run
  Gl gl;
  Absent<std::vector<nlohmann::json>> runs;  // earlier runs resumed into this folder

  template <class V>
  void visit(V& v) {
    v("experiment", experiment);
    v("config_hash", configHash);
    v("code_version", codeVersion);
    v("started", started);
    v("finished", finished);
    v("shard", shard);
    v("gl", gl);
    v("runs", runs);
  }
};

// Reads DIR/meta.json; InputError naming the file when it is missing or malformed.
RunMeta readRunMeta(const std::filesystem::path& directory);

}  // namespace canopy
