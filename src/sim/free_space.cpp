// Free space and routes for the target (src/sim/free_space.hpp).
#include "free_space.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>

#include "../core/no_fma.hpp"

OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim::generator {

FreeSpace::FreeSpace(const std::vector<Shape>& statics, double half_w, double half_h, double required,
                     double margin, double cell)
    : half_w_(half_w), half_h_(half_h), cell_(cell) {
  nx_ = std::max(1, static_cast<int>(std::floor(2.0 * half_w / cell)) + 1);
  ny_ = std::max(1, static_cast<int>(std::floor(2.0 * half_h / cell)) + 1);
  grade_.assign(static_cast<std::size_t>(nx_) * ny_, kFree);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      const Vec2 p = center(i, j);
      char& grade = grade_[index(i, j)];
      for (const Shape& s : statics) {
        if ((p - s.center).norm() - bounding_radius(s) >= required + margin) continue;
        const double d = signed_distance(s, p);
        if (d < required) {
          grade = kBlocked;
          break;
        }
        if (d < required + margin) grade = kPassable;
      }
    }
}

Vec2 FreeSpace::center(int i, int j) const { return {-half_w_ + i * cell_, -half_h_ + j * cell_}; }

std::size_t FreeSpace::index(int i, int j) const { return static_cast<std::size_t>(j) * nx_ + i; }

std::pair<int, int> FreeSpace::cell_of(const Vec2& p) const {
  return {std::clamp(static_cast<int>(std::lround((p.x() + half_w_) / cell_)), 0, nx_ - 1),
          std::clamp(static_cast<int>(std::lround((p.y() + half_h_) / cell_)), 0, ny_ - 1)};
}

bool FreeSpace::free(const Vec2& p) const {
  const auto [i, j] = cell_of(p);
  return grade_[index(i, j)] == kFree;
}

std::vector<Vec2> FreeSpace::route(const Vec2& from, const Vec2& to) const {
  const auto [si, sj] = cell_of(from);
  const auto [gi, gj] = cell_of(to);
  const std::size_t start = index(si, sj), goal = index(gi, gj);
  if (grade_[goal] != kFree) return {};
  // Integer costs (10 per straight step, 14 per diagonal one, four times that through merely passable
  // cells) and the octile heuristic: exact arithmetic, so that ties between equally short routes are broken
  // the same way by every compiler and instruction set.
  const std::size_t n = grade_.size();
  constexpr std::int64_t kUnreached = std::numeric_limits<std::int64_t>::max();
  std::vector<std::int64_t> cost(n, kUnreached);
  std::vector<std::int32_t> parent(n, -1);
  std::vector<char> closed(n, 0);
  using Entry = std::pair<std::int64_t, std::size_t>;  // (cost + heuristic, cell): ties broken by cell index
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  auto heuristic = [&, gi = gi, gj = gj](std::size_t c) -> std::int64_t {
    const std::int64_t di = std::abs(static_cast<int>(c % nx_) - gi), dj = std::abs(static_cast<int>(c / nx_) - gj);
    return 10 * std::max(di, dj) + 4 * std::min(di, dj);
  };
  cost[start] = 0;
  open.push({heuristic(start), start});
  static constexpr int kDi[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static constexpr int kDj[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const std::size_t c = open.top().second;
    open.pop();
    if (closed[c]) continue;
    closed[c] = 1;
    if (c == goal) break;
    const int ci = static_cast<int>(c % nx_), cj = static_cast<int>(c / nx_);
    for (int d = 0; d < 8; ++d) {
      const int i = ci + kDi[d], j = cj + kDj[d];
      if (i < 0 || j < 0 || i >= nx_ || j >= ny_) continue;
      const std::size_t m = index(i, j);
      if (grade_[m] == kBlocked || closed[m]) continue;
      if (d >= 4 && (grade_[index(i, cj)] == kBlocked || grade_[index(ci, j)] == kBlocked)) continue;
      const std::int64_t next = cost[c] + (grade_[m] == kFree ? 1 : 4) * (d < 4 ? 10 : 14);
      if (next < cost[m]) {
        cost[m] = next;
        parent[m] = static_cast<std::int32_t>(c);
        open.push({next + heuristic(m), m});
      }
    }
  }
  if (!closed[goal]) return {};
  std::vector<Vec2> cells;
  for (std::int64_t c = static_cast<std::int64_t>(goal); c != static_cast<std::int64_t>(start); c = parent[c])
    cells.push_back(center(static_cast<int>(c % nx_), static_cast<int>(c / nx_)));
  std::reverse(cells.begin(), cells.end());
  std::vector<Vec2> route{from};
  route.insert(route.end(), cells.begin(), cells.end());
  route.push_back(to);
  return route;
}

}  // namespace occtrack::sim::generator
