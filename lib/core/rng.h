// PCG32 random number generator (O'Neill 2014) with independent streams and O(log n)
// skip-ahead, plus the seeding scheme of the project: a stream is a pure function of
// (seed, key, index) and its d-th uniform is a pure function of (seed, key, index, d).
#pragma once

#include <cstdint>

#include "lib/core/hash.h"
#include "lib/core/math.h"

namespace tb {

class Pcg32 {
 public:
  static constexpr uint64_t kDefaultState = 0x853c49e6748fea9bULL;
  static constexpr uint64_t kDefaultStream = 0xda3e39cb94b95bdbULL;
  static constexpr uint64_t kMultiplier = 0x5851f42d4c957f2dULL;

  Pcg32() = default;
  Pcg32(uint64_t sequence_index, uint64_t offset) { set_sequence(sequence_index, offset); }

  // Selects one of 2^63 streams and a starting offset in it (pcg32_srandom_r).
  void set_sequence(uint64_t sequence_index, uint64_t offset) {
    state_ = 0u;
    inc_ = (sequence_index << 1u) | 1u;
    next_u32();
    state_ += offset;
    next_u32();
  }

  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * kMultiplier + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }

  // Jumps ahead by delta outputs in O(log delta) (Brown 1994, "Random number generation
  // with arbitrary strides").
  void advance(uint64_t delta) {
    uint64_t cur_mult = kMultiplier, cur_plus = inc_, acc_mult = 1u, acc_plus = 0u;
    while (delta > 0) {
      if (delta & 1u) {
        acc_mult *= cur_mult;
        acc_plus = acc_plus * cur_mult + cur_plus;
      }
      cur_plus = (cur_mult + 1u) * cur_plus;
      cur_mult *= cur_mult;
      delta >>= 1u;
    }
    state_ = acc_mult * state_ + acc_plus;
  }

  bool operator==(const Pcg32&) const = default;

 private:
  uint64_t state_ = kDefaultState;
  uint64_t inc_ = kDefaultStream;
};

// A stream of uniform doubles. Each uniform consumes two PCG32 outputs and has 53 random
// bits, so it lies in [0, 1 - 2^-53].
class Rng {
 public:
  Rng() = default;
  explicit Rng(uint64_t seed) : pcg_(hash_values(seed, 0x5eedULL), mix_bits(seed)) {}

  // The stream for (seed, key, index): seed is the run seed, key names what is sampled
  // (a pixel, a chain, a replicate, a hashed check name), index the sample number.
  static Rng for_sample(uint64_t seed, uint64_t key, uint64_t index) {
    Rng r;
    r.pcg_.set_sequence(hash_values(seed, key), hash_values(index, seed, key));
    return r;
  }

  uint32_t next_u32() { return pcg_.next_u32(); }
  uint64_t next_u64() {
    const uint64_t hi = pcg_.next_u32();
    return (hi << 32) | pcg_.next_u32();
  }
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1p-53; }
  Vec2 uniform2() {
    const double a = uniform();
    return {a, uniform()};
  }
  // Uniform integer in [0, n) without modulo bias (Lemire 2019).
  uint32_t uniform_below(uint32_t n) {
    uint64_t m = static_cast<uint64_t>(next_u32()) * n;
    uint32_t l = static_cast<uint32_t>(m);
    if (l < n) {
      const uint32_t t = (0u - n) % n;
      while (l < t) {
        m = static_cast<uint64_t>(next_u32()) * n;
        l = static_cast<uint32_t>(m);
      }
    }
    return static_cast<uint32_t>(m >> 32);
  }

  // Skips `dims` uniforms (each uses two 32-bit outputs).
  void skip_uniforms(uint64_t dims) { pcg_.advance(2 * dims); }

  // The dim-th uniform of the stream (seed, key, index): a pure function of its arguments.
  static double uniform_at(uint64_t seed, uint64_t key, uint64_t index, uint64_t dim) {
    Rng r = for_sample(seed, key, index);
    r.skip_uniforms(dim);
    return r.uniform();
  }

  bool operator==(const Rng&) const = default;

 private:
  Pcg32 pcg_;
};

}  // namespace tb
