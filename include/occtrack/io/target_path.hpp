// Recorded target paths as text tables (CSV, or columns split by spaces or tabs): one row per sample, a time
// and a position in the world's frame. The input of `occtrack scenario import` (sim/recorded_path.hpp makes a
// scenario of it); the format is described in scenarios/README.md, "Your own recorded target paths".
#pragma once

#include <string>
#include <vector>

#include "occtrack/core/scenario.hpp"
#include "occtrack/io/error.hpp"

namespace occtrack::io {

/// Which columns hold the time and the position, and the time's unit.
struct TargetPathColumns {
  /// Each a 0-based column index ("0") or a name in the table's header row ("%time",
  /// "field.pose.pose.position.x"). Default: time, x, y in the first three columns.
  std::string time = "0", x = "1", y = "2";
  /// Multiplies the time column to make seconds: 1e-9 for nanoseconds (`rostopic echo -p` writes %time so).
  double time_scale = 1.0;
};

/// Reads the samples in the file's order, times scaled but not shifted (a recording's clock may start
/// anywhere). Rows are split at commas when the row holds one, else at runs of spaces and tabs; blank lines
/// and lines starting with '#' are skipped; the first row is a header when one of its chosen columns is not a
/// number. Throws InputError naming the file and the line: a file that cannot be read, a column name not in the
/// header (or a name without a header), a row without a chosen column, a value that is not a finite number,
/// times that do not strictly increase, fewer than two samples.
std::vector<core::TargetWaypoint> read_target_path(const std::string& path, const TargetPathColumns& columns = {});

/// The same from the table's text; `source` names it in messages.
std::vector<core::TargetWaypoint> parse_target_path(const std::string& text, const std::string& source,
                                                    const TargetPathColumns& columns = {});

}  // namespace occtrack::io
