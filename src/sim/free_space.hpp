// Free space for the target's centre, and shortest routes through it (private to the scenario generator,
// src/sim/target_path.cpp).
//
// A grid over the area. A cell is passable when its centre keeps the required clearance from every static
// obstacle, and free when it keeps a margin more; routes are shortest paths on the 8-connected grid (A*)
// that avoid merely passable cells where they can (so that the target can follow them smoothly, yet leave a
// spot close to an obstacle).
#pragma once

#include <utility>
#include <vector>

#include "occtrack/sim/geometry.hpp"

namespace occtrack::sim::generator {

class FreeSpace {
 public:
  /// The area is [-half_w, half_w] x [-half_h, half_h]; cells of edge `cell`.
  FreeSpace(const std::vector<Shape>& statics, double half_w, double half_h, double required, double margin,
            double cell);

  /// Whether the cell holding p is free.
  bool free(const Vec2& p) const;

  /// Shortest route of cell centres from `from` to `to` (both ends included as given); empty when `to` is not
  /// free or cannot be reached.
  std::vector<Vec2> route(const Vec2& from, const Vec2& to) const;

 private:
  static constexpr char kBlocked = 0, kPassable = 1, kFree = 2;
  // Defined in free_space.cpp, which is compiled without fused multiply-adds (src/sim/generator_support.hpp).
  Vec2 center(int i, int j) const;
  std::size_t index(int i, int j) const;
  std::pair<int, int> cell_of(const Vec2& p) const;

  double half_w_, half_h_, cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<char> grade_;
};

}  // namespace occtrack::sim::generator
