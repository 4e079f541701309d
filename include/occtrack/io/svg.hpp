// Episode figures: one standalone SVG document per episode, drawn like the paper's comparison figures
// (paper.tex, Figs. "1m_comparison" and "2m_comparison"): a top-down view of the world with the target's path,
// the robot's path coloured by whether the target was visible, and the plans of a few planning cycles.
#pragma once

#include <string>

#include "occtrack/core/episode_record.hpp"
#include "occtrack/core/scenario.hpp"

namespace occtrack::io {

struct SvgOptions {
  /// Width of the whole document in pixels; the height follows from the world's aspect ratio (equal scaling on
  /// both axes) plus the title above and the legend below. At least 300, so that the legend fits.
  int width_px = 900;
  /// Free space around everything drawn, metres. Finite and not negative.
  double margin_m = 1.5;
  /// Draw each snapshot's candidate trajectories (thin, light grey) behind its chosen plan.
  bool candidates = true;
  /// Trace samples between drawn lines of sight at occluded instants: the 1st, (1+n)-th, (1+2n)-th... occluded
  /// sample gets a thin red line robot -> target. 0 draws none.
  int sight_lines_every = 10;
  /// First line of the figure; empty: "<scenario> — <planner>" from the metrics.
  std::string title;

  bool operator==(const SvgOptions&) const = default;
  /// False, with the broken rule in `error` when given, for a width below 300 px, a negative or non-finite
  /// margin, or a negative sight_lines_every.
  bool validate(std::string* error = nullptr) const;
};

/// Where the world lands in the document: the world window [x_min, x_max] x [y_min, y_max] (metres) maps onto
/// the plot rectangle whose top-left pixel is (left_px, top_px), at `scale` pixels per metre on both axes and
/// with y pointing up: pixel = (left_px + scale (x - x_min), top_px + scale (y_max - y)).
struct SvgFrame {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
  double scale = 1;
  double left_px = 0, top_px = 0;
  int width_px = 0, height_px = 0;  ///< the whole document

  core::Vec2 to_px(const core::Vec2& world) const {
    return {left_px + scale * (world.x() - x_min), top_px + scale * (y_max - world.y())};
  }
};

/// The frame episode_svg draws in. The window is the bounding box of the obstacles (at t = 0 and at every
/// vertex of a moving obstacle's path), the trace's robot and target positions and the snapshots' robot,
/// target and plan points, grown by margin_m on every side (non-finite points are ignored; an empty union is
/// a 1 m square around the robot's start). A window taller than 1.5 times the plot's width is widened in x
/// about its centre so that the document stays at most about 1.5 times as tall as it is wide.
/// Throws std::invalid_argument for invalid options.
SvgFrame episode_svg_frame(const core::Scenario& scenario, const core::Trace& trace, const SvgOptions& options = {});

/// The episode as a standalone SVG document (no external resources, UTF-8, starts with "<svg"): a 1 m grid
/// with metre labels on the left and bottom edges; obstacles filled grey at t = 0 (boxes rotated by their
/// yaw), a moving obstacle's path dashed with a light outline of the shape at the path's far end; the target's
/// path dark with a ring at its start and a dot at its end; the robot's path blue where the target was
/// visible and red where it was occluded (each trace sample owns the path from the midpoints to its
/// neighbours, so that a single occluded sample shows); thin red lines of sight at occluded instants (see
/// SvgOptions::sight_lines_every); per snapshot its candidates (light grey), its chosen plan (green), the
/// robot (a disk of scenario.robot_radius), the target (a star) and the time; a legend below the plot, never
/// over it; and above it the title and a metrics line (occlusion time, collisions, success, mean compute).
///
/// Coordinates are pixels rounded to 0.01 and polylines are thinned to within 0.2 px of the original
/// (Douglas-Peucker), so that a long episode stays small (150 s traced every 0.05 s: tens of kilobytes).
/// Non-finite points are skipped: a polyline breaks where one occurs. Text is escaped for XML.
/// Throws std::invalid_argument for invalid options or a trace whose time, robot, target and occluded
/// lists differ in length.
std::string episode_svg(const core::Scenario& scenario, const core::Trace& trace, const core::EpisodeMetrics& metrics,
                        const SvgOptions& options = {});

}  // namespace occtrack::io
