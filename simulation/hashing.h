// Stateless hashing for deterministic per-item randomness (textures per
// wall, noise per pixel, seeds per frame): the same inputs give the same
// bits on every platform and build, unlike std::hash.
#ifndef CATGRAPH_SIMULATION_HASHING_H_
#define CATGRAPH_SIMULATION_HASHING_H_

#include <cstdint>
#include <string_view>

namespace catgraph {

// SplitMix64's finaliser (Steele, Lea & Flood 2014): a bijective mix of x.
constexpr std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// FNV-1a of a string.
constexpr std::uint64_t StableHash(std::string_view text) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : text) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  return h;
}

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_HASHING_H_
