// A straightforward implementation of shared/spec/projection.md that follows the page line by line: full
// stacked constraint matrices (P repeated N times for the obstacles), angles from atan2 and directions from
// cos and sin, one sample and one axis at a time. It is not meant to be fast: it exists as an
// independent oracle for the tests and as the baseline that `occtrack bench projection --literal` and
// docs/benchmarks.md compare the fast Projector against. Use Projector for real work.
#pragma once

#include <memory>
#include <string>

#include "occtrack/projection/projector.hpp"

namespace occtrack::projection {

template <typename T>
class LiteralProjector {
 public:
  explicit LiteralProjector(const Settings& settings);  // throws std::invalid_argument on bad settings
  ~LiteralProjector();
  LiteralProjector(const LiteralProjector&) = delete;
  LiteralProjector& operator=(const LiteralProjector&) = delete;

  bool solve(const Problem<T>& problem, Result<T>& result, std::string* error = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

extern template class LiteralProjector<float>;
extern template class LiteralProjector<double>;

}  // namespace occtrack::projection
