// Size and finiteness checks of projection inputs and outputs (private to src/projection).
#pragma once

#include <cmath>
#include <sstream>
#include <string>

#include "occtrack/projection/projector.hpp"

namespace occtrack::projection::detail {

template <typename M>
bool check_shape(const M& matrix, const char* field, int rows, int cols, std::string* error) {
  if (matrix.rows() == rows && matrix.cols() == cols) return true;
  if (error != nullptr) {
    std::ostringstream out;
    out << field << " has shape " << matrix.rows() << " x " << matrix.cols() << ", expected " << rows << " x "
        << cols;
    *error = out.str();
  }
  return false;
}

template <typename M>
bool check_finite(const M& matrix, const char* field, std::string* error) {
  if (matrix.allFinite()) return true;
  for (Eigen::Index r = 0; r < matrix.rows(); ++r)
    for (Eigen::Index c = 0; c < matrix.cols(); ++c)
      if (!std::isfinite(matrix(r, c))) {
        if (error != nullptr) {
          std::ostringstream out;
          out << field << " [sample " << r << ", column " << c << "] is not finite (" << matrix(r, c) << ")";
          *error = out.str();
        }
        return false;
      }
  return false;
}

template <typename T>
bool check_problem(const Settings& s, const Problem<T>& p, std::string* error) {
  const int B = s.batch, n2 = 2 * s.coefficients(), m = s.steps;
  struct Field {
    const RowMatrix<T>* matrix;
    const char* name;
    int cols;
  };
  const Field fields[] = {{&p.robot_velocity, "problem.robot_velocity", 2},
                          {&p.obstacles, "problem.obstacles", 4 * s.obstacles},
                          {&p.target, "problem.target", 4},
                          {&p.terminal, "problem.terminal", 4},
                          {&p.via_points, "problem.via_points", 4},
                          {&p.lambda0, "problem.lambda0", n2},
                          {&p.distance_min, "problem.distance_min", m},
                          {&p.distance_max, "problem.distance_max", m},
                          {&p.xi_bar, "problem.xi_bar", n2}};
  for (const Field& f : fields)
    if (!check_shape(*f.matrix, f.name, B, f.cols, error)) return false;
  for (const Field& f : fields)
    if (!check_finite(*f.matrix, f.name, error)) return false;
  return true;
}

template <typename T>
bool check_result(const Settings& s, const Result<T>& r, std::string* error) {
  const int B = s.batch, n2 = 2 * s.coefficients();
  if (!check_shape(r.xi_init, "result.xi_init", B, n2, error)) return false;
  if (!check_shape(r.xi, "result.xi", B, n2, error)) return false;
  if (r.residual.size() != B) return check_shape(r.residual, "result.residual", B, 1, error);
  const int history_rows = s.record_residual_history ? B : 0;
  const int history_cols = s.record_residual_history ? s.iterations : 0;
  return check_shape(r.residual_history, "result.residual_history", history_rows, history_cols, error);
}

}  // namespace occtrack::projection::detail
