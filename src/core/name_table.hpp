// Enum spellings as one table read in both directions (private to the run-time library):
//
//   constexpr std::pair<Kind, const char*> kKindNames[] = {{Kind::a, "a"}, {Kind::b, "b"}};
//   const char* to_string(Kind k) { return detail::name_of(kKindNames, k); }
//   std::optional<Kind> parse_kind(std::string_view t) { return detail::value_of(kKindNames, t); }
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>

namespace occtrack::detail {

/// The spelling of `value`, or "?" when the table lacks it.
template <typename Enum, std::size_t N>
const char* name_of(const std::pair<Enum, const char*> (&table)[N], Enum value) {
  for (const auto& [v, name] : table)
    if (v == value) return name;
  return "?";
}

/// The value spelled `text`, or nullopt.
template <typename Enum, std::size_t N>
std::optional<Enum> value_of(const std::pair<Enum, const char*> (&table)[N], std::string_view text) {
  for (const auto& [v, name] : table)
    if (text == name) return v;
  return std::nullopt;
}

}  // namespace occtrack::detail
