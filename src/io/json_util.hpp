// Checked access to JSON documents for occtrack's readers (private to src/io). Every failure throws
// InputError with "SOURCE: KEY.PATH: rule" so that the user can find the broken value.
#pragma once

#include <nlohmann/json.hpp>
#include <initializer_list>
#include <string>
#include <vector>

#include "occtrack/io/error.hpp"

namespace occtrack::io::detail {

using nlohmann::json;

class JsonReader {
 public:
  explicit JsonReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& rule) const;

  /// Member `key` of object `parent` (at `path`), which must exist.
  const json& member(const json& parent, const std::string& path, const std::string& key) const;
  /// Fails when `object` has a key not in `allowed`.
  void only_keys(const json& object, const std::string& path, std::initializer_list<const char*> allowed) const;
  void require_object(const json& value, const std::string& path) const;

  double number(const json& value, const std::string& path) const;  // finite
  int integer(const json& value, const std::string& path) const;
  std::string string(const json& value, const std::string& path) const;
  /// A list of exactly `size` finite numbers (size < 0: any length).
  std::vector<double> numbers(const json& value, const std::string& path, int size) const;

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

/// `text` (a key or value from the file) fit for a message: control characters and NUL written as \xNN, the
/// rest unchanged. A NUL would end the message at what() (the CLI prints only that far).
std::string printable(const std::string& text);

json parse_json_text(const std::string& text, const std::string& source);
std::string read_text_file(const std::string& path);

}  // namespace occtrack::io::detail
