#pragma once
// Internal: SplitMix64, the same sequence on every platform and standard library (std::
// distributions are implementation-defined). Seeds derive from the user's seed only.

#include <cstdint>

namespace mcgim::detail {

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
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  std::uint64_t state_;
};

/// A seed for a sub-stream, from a seed and a stream id.
inline std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
  Rng r(seed * 0x100000001B3ull ^ (stream + 0x632BE59BD9B4E019ull));
  return r.next();
}

}  // namespace mcgim::detail
