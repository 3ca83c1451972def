// The libFuzzer entry point of one target, chosen at build time (CANOPY_FUZZ_TARGET, the index
// into canopy::fuzz::targets()); built only by the fuzz preset (tests/fuzz/CMakeLists.txt).
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  canopy::fuzz::targets().at(CANOPY_FUZZ_TARGET).run(data, size);
  return 0;
}
