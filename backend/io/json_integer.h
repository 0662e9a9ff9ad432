// Integers read from JSON with their range checked. nlohmann's get<int>()
// of a number outside int's range (8e22, 1e130) is undefined behaviour, and
// a count read unchecked can ask for a loop of 10^15 (both found by
// fuzzing, docs/fuzzing.md).
#ifndef CATGRAPH_BACKEND_IO_JSON_INTEGER_H_
#define CATGRAPH_BACKEND_IO_JSON_INTEGER_H_

#include <cstdint>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace catgraph {

// `v` as an integer in [lo, hi]; otherwise std::invalid_argument naming
// `what` and the value found.
inline std::int64_t IntegerIn(const nlohmann::json& v, const std::string& what, std::int64_t lo, std::int64_t hi) {
  const bool integer = v.is_number_integer() &&
                       !(v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi));
  if (!integer || v.get<std::int64_t>() < lo || v.get<std::int64_t>() > hi) {
    throw std::invalid_argument("'" + what + "' must be an integer from " + std::to_string(lo) + " to " +
                                std::to_string(hi) + ", not " + v.dump());
  }
  return v.get<std::int64_t>();
}

// IntegerIn for an optional key of the object `j`.
inline std::int64_t IntegerIn(const nlohmann::json& j, const char* key, std::int64_t fallback, std::int64_t lo,
                              std::int64_t hi) {
  return j.contains(key) ? IntegerIn(j.at(key), key, lo, hi) : fallback;
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_JSON_INTEGER_H_
