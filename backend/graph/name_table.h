// Stable spellings of enum values for files, JSON and the command line.
#ifndef CATGRAPH_BACKEND_GRAPH_NAME_TABLE_H_
#define CATGRAPH_BACKEND_GRAPH_NAME_TABLE_H_

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace catgraph {

template <typename Enum, std::size_t N>
using NameTable = std::array<std::pair<Enum, std::string_view>, N>;

// The name of `value`; the first entry's name if the table lacks it.
template <typename Enum, std::size_t N>
constexpr std::string_view NameOf(const NameTable<Enum, N>& table, Enum value) {
  for (const auto& [v, name] : table) {
    if (v == value) return name;
  }
  return table.front().second;
}

template <typename Enum, std::size_t N>
constexpr std::optional<Enum> ValueOf(const NameTable<Enum, N>& table, std::string_view name) {
  for (const auto& [v, n] : table) {
    if (n == name) return v;
  }
  return std::nullopt;
}

// Every name, in table order (for the command line's choices).
template <typename Enum, std::size_t N>
std::vector<std::string> NamesOf(const NameTable<Enum, N>& table) {
  std::vector<std::string> names;
  for (const auto& [v, name] : table) names.emplace_back(name);
  return names;
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_NAME_TABLE_H_
