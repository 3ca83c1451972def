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
// `git rev-parse HEAD` of the source tree the binary was built from (read at build time),
// "+dirty" when its code (common, methods, bench, viewer, the build files) was modified;
// "unknown" outside a checkout.
std::string gitCommit();
// gitCommit(), and for a modified tree a hash of the change ("<commit>+dirty.<first 16 hex of
// the SHA-256 of the diff>"): what a resumed run must match.
std::string codeVersion();
std::string isoTimestampUtc();

}  // namespace canopy
