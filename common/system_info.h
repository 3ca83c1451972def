#pragma once

#include <cstdint>
#include <string>

namespace canopy {

// Peak resident set size of this process (VmHWM), bytes.
uint64_t peakRssBytes();
// Resets the peak to the current RSS (Linux clear_refs); false when the kernel refuses, in which
// case peaks measured afterwards are process-wide.
bool resetPeakRss();
std::string cpuModel();
// `git rev-parse HEAD` of the source tree the binary was built from, "+dirty" when modified;
// "unknown" outside a checkout.
std::string gitCommit();
std::string isoTimestampUtc();

}  // namespace canopy
