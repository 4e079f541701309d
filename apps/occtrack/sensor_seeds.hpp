// The list of sensor seeds a command runs its suites at (`bench suite --sensor-seeds`, `bench paper
// --sensor-seeds`): one home for how the list is written and checked.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace occtrack::app {

/// At most this many seeds in one list.
inline constexpr std::size_t kMaxSensorDraws = 1000;

/// Adds --sensor-seeds to `cmd`: a comma-separated list of items "S" or "A-B" (1-10, 1,4,7, 2-4,9), split
/// by CLI11 into `items`, each item checked as it is parsed (an empty item is dropped, as for the other list
/// options). `description` is the help text.
CLI::Option* add_sensor_seeds_option(CLI::App* cmd, std::vector<std::string>& items, const std::string& description);

/// The seeds the items name, in the order written. Throws std::invalid_argument naming --sensor-seeds on a
/// bad item, a range that runs backwards, a repeated seed or more than kMaxSensorDraws of them.
std::vector<std::uint64_t> expand_sensor_seeds(const std::vector<std::string>& items);

/// "1,2,3": the seeds as the settings lines write them.
std::string sensor_seeds_text(const std::vector<std::uint64_t>& seeds);

}  // namespace occtrack::app
