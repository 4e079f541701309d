#include "sensor_seeds.hpp"

#include <set>
#include <stdexcept>
#include <utility>

#include "episode_common.hpp"

namespace occtrack::app {

namespace {

std::uint64_t seed_number(const std::string& text) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > 19)
    throw std::invalid_argument("\"" + text + "\" is not a seed (an integer >= 0 of at most 19 digits)");
  return std::stoull(text);
}

/// One item, "S" or "A-B", as its first and last seed. Throws std::invalid_argument with the rule broken.
std::pair<std::uint64_t, std::uint64_t> seed_range(const std::string& item) {
  const std::size_t dash = item.find('-');
  const std::uint64_t first = seed_number(item.substr(0, dash));
  const std::uint64_t last = dash == std::string::npos ? first : seed_number(item.substr(dash + 1));
  if (last < first) throw std::invalid_argument("the range " + item + " runs backwards");
  return {first, last};
}

std::string seed_item_rule(const std::string& item) {
  try {
    seed_range(item);
    return "";
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
}

}  // namespace

CLI::Option* add_sensor_seeds_option(CLI::App* cmd, std::vector<std::string>& items, const std::string& description) {
  return cmd->add_option("--sensor-seeds", items, description)
      ->delimiter(',')
      ->check(episode_cli::validator(seed_item_rule, "LIST"));
}

std::vector<std::uint64_t> expand_sensor_seeds(const std::vector<std::string>& items) {
  std::vector<std::uint64_t> seeds;
  std::set<std::uint64_t> seen;
  for (const auto& item : items) {
    std::pair<std::uint64_t, std::uint64_t> range;
    try {
      range = seed_range(item);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--sensor-seeds: ") + e.what());
    }
    for (std::uint64_t s = range.first;; ++s) {
      if (!seen.insert(s).second)
        throw std::invalid_argument("--sensor-seeds: seed " + std::to_string(s) + " is given twice");
      seeds.push_back(s);
      if (seeds.size() > kMaxSensorDraws)
        throw std::invalid_argument("--sensor-seeds: more than " + std::to_string(kMaxSensorDraws) + " seeds");
      if (s == range.second) break;
    }
  }
  return seeds;
}

std::string sensor_seeds_text(const std::vector<std::uint64_t>& seeds) {
  std::string text;
  for (const std::uint64_t s : seeds) text += (text.empty() ? "" : ",") + std::to_string(s);
  return text;
}

}  // namespace occtrack::app
