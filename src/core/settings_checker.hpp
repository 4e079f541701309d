// The first broken rule of a settings struct, as a message (private to the run-time library). Checks after
// the first failure are skipped, so that validate() names one field, the first in declaration order:
//
//   detail::SettingsChecker c;
//   c.require(steps >= 4, "steps (", steps, ") must be at least 4");
//   c.finite(horizon, "horizon");
//   return c.done(error);
//
// Numbers are written as an ostream with precision 12 writes them (printf's "%.12g"), but with
// std::to_chars, into a string: a checker given a kept string (the Tracker's) formats its message without
// touching the heap while the message fits that string's capacity.
#pragma once

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

namespace occtrack::detail {

class SettingsChecker {
 public:
  /// The message goes into the checker's own string.
  SettingsChecker() : message_(own_) {}
  /// The message goes into `sink`, which is cleared; its storage is reused.
  explicit SettingsChecker(std::string& sink) : message_(sink) { message_.clear(); }
  SettingsChecker(const SettingsChecker&) = delete;
  SettingsChecker& operator=(const SettingsChecker&) = delete;

  template <typename... Parts>
  void require(bool ok, const Parts&... parts) {
    if (ok || !message_.empty()) return;
    (append(parts), ...);
    if (message_.empty()) message_ = "invalid setting";  // an empty message would read as "no failure"
  }
  void finite(double value, const char* field) {
    require(std::isfinite(value), field, " must be a finite number, got ", value);
  }
  void positive(double value, const char* field) {
    require(std::isfinite(value) && value > 0.0, field, " must be a positive number, got ", value);
  }
  void non_negative(double value, const char* field) {
    require(std::isfinite(value) && value >= 0.0, field, " must be a finite number >= 0, got ", value);
  }
  void range(double lo, double hi, const char* lo_field, const char* hi_field) {
    require(lo <= hi, lo_field, " (", lo, ") must not exceed ", hi_field, " (", hi, ")");
  }
  void share(double value, const char* field) {
    require(std::isfinite(value) && value >= 0.0 && value <= 1.0, field, " must lie in [0, 1], got ", value);
  }
  bool ok() const { return message_.empty(); }
  const std::string& message() const { return message_; }
  /// True when every rule held; otherwise false, with *error (when given) the first broken rule.
  bool done(std::string* error) const {
    if (error && error != &message_ && !message_.empty()) *error = message_;
    return message_.empty();
  }

 private:
  template <typename T>
  void append(const T& part) {
    using U = std::decay_t<T>;
    if constexpr (std::is_same_v<U, bool>) {
      message_ += part ? '1' : '0';  // as an ostream without boolalpha
    } else if constexpr (std::is_same_v<U, char>) {
      message_ += part;
    } else if constexpr (std::is_convertible_v<const T&, std::string_view>) {
      message_ += std::string_view(part);
    } else if constexpr (std::is_integral_v<U>) {
      char text[24];
      const std::to_chars_result r = std::to_chars(text, text + sizeof text, part);
      message_.append(text, r.ptr);
    } else if constexpr (std::is_same_v<U, double> || std::is_same_v<U, float>) {
      char text[32];  // "%.12g" needs at most 19 characters
      const std::to_chars_result r =
          std::to_chars(text, text + sizeof text, static_cast<double>(part), std::chars_format::general, 12);
      message_.append(text, r.ptr);
    } else {
      static_assert(kNotWritten<U>, "a message part is text, a character, an integer or floating point");
    }
  }
  template <typename>
  static constexpr bool kNotWritten = false;

  std::string own_;
  std::string& message_;
};

/// `settings` when settings.validate() holds; otherwise throws std::invalid_argument "WHO: <its message>".
/// Constructors call it first, before building anything from the settings.
template <typename Settings>
const Settings& checked(const Settings& settings, const std::string& who) {
  std::string error;
  if (!settings.validate(&error)) throw std::invalid_argument(who + ": " + error);
  return settings;
}

}  // namespace occtrack::detail
