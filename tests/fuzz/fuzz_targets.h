#pragma once

// The fuzz targets: each feeds one input to a reader of user files exactly as canopy-bench does,
// and accepts an InputError (the contract's exit 2) as the right answer to a bad input. Any other
// exception, a crash or a sanitizer report is a bug. They are built twice: as libFuzzer harnesses
// (make fuzz, tests/fuzz/fuzz_main.cpp) and into the test suite, which replays the committed seed
// corpus and every regression input (tests/fuzz/corpus/<target>/,
// tests/fuzz/regressions/<target>/).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace canopy::fuzz {

struct Target {
  const char* name;  // also the corpus folder's name
  void (*run)(const uint8_t* data, size_t size);
};

// config: the bytes as an experiment config (parseJson, then every section and method parameter).
void runConfig(const uint8_t* data, size_t size);
// tree_loader: byte 0 picks the format (OBJ, glTF, GLB), the rest is the model file, next to a
// valid material library and leaf texture it may refer to (tree.mtl, leaf.png).
void runTreeLoader(const uint8_t* data, size_t size);
// captures: the bytes as transforms_train.json of a NeRF capture folder whose images and
// transforms_test.json are valid.
void runCaptures(const uint8_t* data, size_t size);
// camera_path: the bytes as a recorded camera path.
void runCameraPath(const uint8_t* data, size_t size);
// asset_loader: byte 0 picks a method, byte 1 one file of its baked asset (asset.json, a blob, an
// image); the rest replaces that file, then Method::load reads the folder.
void runAssetLoader(const uint8_t* data, size_t size);

const std::vector<Target>& targets();

}  // namespace canopy::fuzz
