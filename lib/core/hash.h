// 64-bit hashing used to derive scrambled, counter-based seeds (docs/validation.md, "Budget,
// seeds and determinism"): a seed is a pure function of (run seed, stream key, index), never
// of a thread id or of time.
#pragma once

#include <cstdint>
#include <string_view>

namespace tb {

// MurmurHash3 fmix64 finaliser: a bijection on 64-bit integers with full avalanche.
constexpr uint64_t mix_bits(uint64_t v) {
  v ^= v >> 33;
  v *= 0xff51afd7ed558ccdULL;
  v ^= v >> 33;
  v *= 0xc4ceb9fe1a85ec53ULL;
  v ^= v >> 33;
  return v;
}

constexpr uint64_t hash_combine(uint64_t h, uint64_t v) {
  // Boost-style combine on top of a full mix of the value, so that (a, b) != (b, a).
  return mix_bits(h ^ (mix_bits(v + 0x9e3779b97f4a7c15ULL) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2)));
}

template <class... Ts>
constexpr uint64_t hash_values(uint64_t first, Ts... rest) {
  uint64_t h = mix_bits(first ^ 0x243f6a8885a308d3ULL);
  ((h = hash_combine(h, static_cast<uint64_t>(rest))), ...);
  return h;
}

// FNV-1a of a string, then mixed: turns a check or test name into a stream key.
constexpr uint64_t hash_string(std::string_view s) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return mix_bits(h);
}

}  // namespace tb
