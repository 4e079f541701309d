// Random numbers, rounding and angles of the scenario generator (src/sim/generator_support.hpp).
#include "generator_support.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "../core/no_fma.hpp"

OCCTRACK_NO_FMA_CONTRACTION

namespace occtrack::sim::generator {

double Random::uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

double Random::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

bool Random::chance(double p) { return uniform() < p; }

std::size_t Random::index(std::size_t n) {
  return std::min(n - 1, static_cast<std::size_t>(uniform() * static_cast<double>(n)));
}

double Random::rising(double lo, double hi) { return lo + (hi - lo) * std::sqrt(uniform()); }

double Random::normal() {
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

double round_to(double x, int decimals) {
  const double scale = std::pow(10.0, decimals);
  const double r = std::round(x * scale) / scale;
  return r == 0.0 ? 0.0 : r;
}

Vec2 round_to(const Vec2& v, int decimals) { return {round_to(v.x(), decimals), round_to(v.y(), decimals)}; }

double wrap_angle(double a) {
  a = std::fmod(a + std::numbers::pi, 2.0 * std::numbers::pi);
  if (a < 0.0) a += 2.0 * std::numbers::pi;
  return a - std::numbers::pi;
}

bool inside_area(const Vec2& p, double half_w, double half_h) {
  return std::abs(p.x()) <= half_w && std::abs(p.y()) <= half_h;
}

}  // namespace occtrack::sim::generator
