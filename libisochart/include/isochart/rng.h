#pragma once
// A small, fast, portable generator (SplitMix64): identical sequences on every platform and
// standard library, unlike std:: distributions. Seeded per chart so thread count never matters.

#include <cstdint>

namespace isochart {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed ^ 0x9E3779B97F4A7C15ull) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return (next() >> 11) * (1.0 / 9007199254740992.0); }
  /// Uniform integer in [0, n).
  std::uint64_t below(std::uint64_t n) { return n ? next() % n : 0; }

 private:
  std::uint64_t state_;
};

/// Mixes several values into one seed (for per-chart seeds from the user seed and chart identity).
inline std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b) {
  Rng r(a * 0x100000001B3ull ^ (b + 0x632BE59BD9B4E019ull + (a << 6) + (a >> 2)));
  return r.next();
}

}  // namespace isochart
