#include "json_util.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace occtrack::io::detail {

namespace {

// Messages quote at most this deep: nlohmann's dump() recurses once per level, and a value nested 100000
// levels deep (a few hundred kilobytes of '[') overflows the stack (tests/test_fuzz_regressions.cpp).
constexpr int kMaxDescribedDepth = 64;

bool deeper_than(const json& value, int levels) {
  if (!value.is_structured()) return false;
  if (levels == 0) return true;
  for (const json& element : value)
    if (deeper_than(element, levels - 1)) return true;
  return false;
}

std::string describe(const json& value) {
  if (deeper_than(value, kMaxDescribedDepth))
    return std::string(value.is_array() ? "a list" : "an object") + " nested more than " +
           std::to_string(kMaxDescribedDepth) + " levels deep";
  std::string text = value.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  return text;
}

}  // namespace

std::string printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
    } else {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 15];
    }
  }
  return out;
}

void JsonReader::fail(const std::string& path, const std::string& rule) const {
  throw InputError(source_ + ": " + path + ": " + rule);
}

const json& JsonReader::member(const json& parent, const std::string& path, const std::string& key) const {
  const std::string full = path.empty() ? key : path + "." + key;
  require_object(parent, path.empty() ? "(top level)" : path);
  const auto it = parent.find(key);
  if (it == parent.end()) fail(full, "missing required key");
  return *it;
}

void JsonReader::only_keys(const json& object, const std::string& path,
                           std::initializer_list<const char*> allowed) const {
  require_object(object, path.empty() ? "(top level)" : path);
  for (auto it = object.begin(); it != object.end(); ++it) {
    bool known = false;
    for (const char* key : allowed) known = known || it.key() == key;
    if (!known) {
      std::string list;
      for (const char* key : allowed) list += std::string(list.empty() ? "" : ", ") + key;
      const std::string key = printable(it.key());
      fail(path.empty() ? key : path + "." + key, "unknown key (expected one of: " + list + ")");
    }
  }
}

void JsonReader::require_object(const json& value, const std::string& path) const {
  if (!value.is_object()) fail(path, "must be an object, got " + describe(value));
}

double JsonReader::number(const json& value, const std::string& path) const {
  // nlohmann parses NaN and Infinity only from non-standard text; strings such as "nan" are caught here too.
  if (!value.is_number()) fail(path, "must be a number, got " + describe(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail(path, "must be a finite number");
  return x;
}

int JsonReader::integer(const json& value, const std::string& path) const {
  if (!value.is_number_integer()) fail(path, "must be an integer, got " + describe(value));
  if (value.is_number_unsigned() && value.get<unsigned long long>() > 1000000000ULL)
    fail(path, "integer out of range: " + describe(value));
  const auto x = value.get<long long>();
  if (x < -1000000000LL || x > 1000000000LL) fail(path, "integer out of range: " + describe(value));
  return static_cast<int>(x);
}

std::string JsonReader::string(const json& value, const std::string& path) const {
  if (!value.is_string()) fail(path, "must be a string, got " + describe(value));
  return value.get<std::string>();
}

std::vector<double> JsonReader::numbers(const json& value, const std::string& path, int size) const {
  if (!value.is_array()) fail(path, "must be a list of numbers, got " + describe(value));
  if (size >= 0 && static_cast<int>(value.size()) != size)
    fail(path, "expected " + std::to_string(size) + " numbers, got " + std::to_string(value.size()));
  std::vector<double> out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) out.push_back(number(value[i], path + "[" + std::to_string(i) + "]"));
  return out;
}

json parse_json_text(const std::string& text, const std::string& source) {
  try {
    return json::parse(text);
  } catch (const json::out_of_range& e) {
    // nlohmann reports a number beyond double's range (1e400) here.
    throw InputError(source + ": a number is not finite or out of range (" + e.what() + ")");
  } catch (const json::exception& e) {
    throw InputError(source + ": not valid JSON (" + e.what() + ")");
  }
}

std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open the file for reading");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read error");
  return buffer.str();
}

}  // namespace occtrack::io::detail
