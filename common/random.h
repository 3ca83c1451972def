#pragma once

#include <cstdint>

namespace canopy {

// A small deterministic generator (PCG32, O'Neill 2014). Standard library distributions are
// implementation-defined, so every random draw in Canopy goes through this class: the same seed
// gives the same tree and the same layout on every platform and compiler.
class Random {
 public:
  explicit Random(uint64_t seed, uint64_t stream = 0x853c49e6748fea9bULL) {
    mIncrement = (stream << 1u) | 1u;
    nextUint();
    mState += seed;
    nextUint();
  }

  uint32_t nextUint() {
    const uint64_t old = mState;
    mState = old * 6364136223846793005ULL + mIncrement;
    const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }

  // Uniform in [0, 1) with 24 bits of precision, exact in float.
  float uniform() { return static_cast<float>(nextUint() >> 8) * (1.0f / 16777216.0f); }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n) (n > 0); the modulo bias is below 2^-32 * n, irrelevant here.
  uint32_t below(uint32_t n) { return static_cast<uint32_t>((uint64_t(nextUint()) * n) >> 32); }

 private:
  uint64_t mState = 0;
  uint64_t mIncrement = 1;
};

}  // namespace canopy
