// What the episode documents share (private to src/io; io/svg, io/html_replay): the check of the trace they
// draw, XML/HTML escaping, and numbers as the figures and pages show them.
#pragma once

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "occtrack/core/episode_record.hpp"

namespace occtrack::io::detail {

/// Throws std::invalid_argument("<who>: trace lists differ in length: ...") unless the trace's time, robot,
/// target and occluded lists have one entry per sample each.
inline void check_trace(const core::Trace& trace, const std::string& who) {
  const std::size_t n = trace.robot.size();
  if (trace.time.size() != n || trace.target.size() != n || trace.occluded.size() != n)
    throw std::invalid_argument(who + ": trace lists differ in length: time " + std::to_string(trace.time.size()) +
                                ", robot " + std::to_string(n) + ", target " + std::to_string(trace.target.size()) +
                                ", occluded " + std::to_string(trace.occluded.size()));
}

/// `text` with & < > " ' escaped, fit for XML and HTML text and attribute values.
inline std::string escape_xml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

/// Fixed notation with `decimals`, or "n/a" for a non-finite value (never "nan" in a document).
inline std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

/// Three significant figures for timings from microseconds to seconds, without exponents.
inline std::string milliseconds(double ms) {
  if (!std::isfinite(ms)) return "n/a";
  return fixed(ms, std::abs(ms) >= 100 ? 0 : std::abs(ms) >= 10 ? 1 : std::abs(ms) >= 1 ? 2 : 3);
}

}  // namespace occtrack::io::detail
