// Recorded target paths (io/target_path.hpp): a text table's time and position columns. Every failure is an
// InputError "SOURCE: line N: rule".
#include "occtrack/io/target_path.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>

namespace occtrack::io {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

// A row's fields: split at commas when it holds one, else at runs of spaces and tabs.
std::vector<std::string_view> split_row(std::string_view row) {
  std::vector<std::string_view> fields;
  if (row.find(',') != std::string_view::npos) {
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = row.find(',', start);
      const std::size_t length = comma == std::string_view::npos ? std::string_view::npos : comma - start;
      fields.push_back(trim(row.substr(start, length)));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    return fields;
  }
  std::size_t i = 0;
  while (i < row.size()) {
    while (i < row.size() && std::isspace(static_cast<unsigned char>(row[i]))) ++i;
    const std::size_t start = i;
    while (i < row.size() && !std::isspace(static_cast<unsigned char>(row[i]))) ++i;
    if (i > start) fields.push_back(row.substr(start, i - start));
  }
  return fields;
}

std::optional<double> parse_number(std::string_view field) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  double x = 0.0;
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), x);
  if (field.empty() || error != std::errc() || end != field.data() + field.size()) return std::nullopt;
  return x;
}

bool is_index(std::string_view name) {
  return !name.empty() && name.size() <= 6 &&
         std::all_of(name.begin(), name.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

std::string quoted(std::string_view s) {
  std::string out = "'";
  for (const char c : s.substr(0, 80)) out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  return out + (s.size() > 80 ? "...'" : "'");
}

struct Column {
  const char* role;  // "time", "x", "y"
  std::string name;  // as given
  std::size_t index = 0;
};

}  // namespace

std::vector<core::TargetWaypoint> parse_target_path(const std::string& text, const std::string& source,
                                                    const TargetPathColumns& columns) {
  const auto error = [&source](int line, const std::string& rule) {
    return InputError(source + ": " + (line > 0 ? "line " + std::to_string(line) + ": " : "") + rule);
  };
  if (!std::isfinite(columns.time_scale) || columns.time_scale <= 0.0)
    throw error(0, "the time scale must be a positive number, got " + std::to_string(columns.time_scale));
  Column chosen[3] = {{"time", columns.time}, {"x", columns.x}, {"y", columns.y}};
  bool named = false;
  for (Column& c : chosen) {
    if (trim(c.name).empty()) throw error(0, std::string("no column given for ") + c.role);
    if (is_index(c.name))
      c.index = static_cast<std::size_t>(std::stoul(c.name));
    else
      named = true;
  }

  std::vector<core::TargetWaypoint> samples;
  bool header_seen = false;
  std::istringstream lines(text);
  std::string raw;
  int line = 0;
  while (std::getline(lines, raw)) {
    ++line;
    const std::string_view row = trim(raw);
    if (row.empty() || row.front() == '#') continue;
    const std::vector<std::string_view> fields = split_row(row);
    if (!header_seen && samples.empty()) {
      // The first row: a header when a column is chosen by name, or when a chosen column is not a number.
      bool header = named;
      for (const Column& c : chosen)
        if (!named && (c.index >= fields.size() || !parse_number(fields[c.index]))) header = true;
      if (header) {
        header_seen = true;
        for (Column& c : chosen) {
          if (is_index(c.name)) continue;
          const auto at = std::find(fields.begin(), fields.end(), trim(c.name));
          if (at == fields.end()) {
            std::string names;
            for (std::size_t k = 0; k < fields.size() && k < 12; ++k) names += (k ? ", " : "") + quoted(fields[k]);
            if (fields.size() > 12) names += ", ...";
            throw error(line, std::string("no column named ") + quoted(c.name) + " (for the " + c.role +
                                  ") in the header; it has " + names);
          }
          c.index = static_cast<std::size_t>(at - fields.begin());
        }
        continue;
      }
    }
    double values[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
      const Column& c = chosen[k];
      if (c.index >= fields.size())
        throw error(line, "no column " + std::to_string(c.index) + " (the " + c.role + "): the row has " +
                              std::to_string(fields.size()) + " fields");
      const std::optional<double> value = parse_number(fields[c.index]);
      if (!value || !std::isfinite(*value))
        throw error(line, std::string("the ") + c.role + " (column " + std::to_string(c.index) +
                              ") must be a finite number, got " + quoted(fields[c.index]));
      values[k] = *value;
    }
    const double time = values[0] * columns.time_scale;
    if (!std::isfinite(time)) throw error(line, "the time times the time scale is not finite");
    if (!samples.empty() && !(time > samples.back().time)) {
      std::ostringstream rule;
      rule.precision(17);
      rule << "times must strictly increase: " << time << " s after " << samples.back().time << " s";
      throw error(line, rule.str());
    }
    samples.push_back({time, core::Vec2(values[1], values[2])});
  }
  if (samples.size() < 2)
    throw error(0, "a target path needs at least two samples, got " + std::to_string(samples.size()));
  return samples;
}

std::vector<core::TargetWaypoint> read_target_path(const std::string& path, const TargetPathColumns& columns) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": cannot open the file");
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError(path + ": cannot read the file");
  return parse_target_path(text.str(), path, columns);
}

}  // namespace occtrack::io
