// The first broken rule of a settings struct, as a message (private to the run-time library). Checks after
// the first failure are skipped, so that validate() names one field, the first in declaration order:
//
//   detail::SettingsChecker c;
//   c.require(steps >= 4, "steps (", steps, ") must be at least 4");
//   c.finite(horizon, "horizon");
//   return c.done(error);
#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace occtrack::detail {

class SettingsChecker {
 public:
  template <typename... Parts>
  void require(bool ok, const Parts&... parts) {
    if (ok || !message_.empty()) return;
    std::ostringstream out;
    out.precision(12);
    (out << ... << parts);
    message_ = out.str();
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
    if (error && !message_.empty()) *error = message_;
    return message_.empty();
  }

 private:
  std::string message_;
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
