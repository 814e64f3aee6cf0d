#pragma once
// PCG32 random numbers (O'Neill, "PCG: A Family of Simple Fast Space-Efficient
// Statistically Good Algorithms for Random Number Generation", 2014): 64-bit
// LCG state, xorshift-high + random-rotate output. Streams let every pixel
// and sample have an independent sequence, so images do not depend on the
// order in which threads process pixels.
#include <cstdint>

namespace raylab {

// SplitMix64 finaliser: spreads nearby integers (seed, pixel, sample) over
// the whole 64-bit range before they seed the generator.
inline uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Pcg32 {
 public:
  Pcg32(uint64_t seed, uint64_t stream) : state_(0), inc_((stream << 1u) | 1u) {
    next();
    state_ += seed;
    next();
  }

  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
  }

  // Uniform float in [0, 1): the top 24 bits, so 1.0 is never returned.
  float uniform() { return static_cast<float>(next() >> 8) * 0x1p-24f; }

 private:
  uint64_t state_;
  uint64_t inc_;
};

}  // namespace raylab
