// Projection case files (format tag "occtrack.projection-case.v1", shared/spec/projection.md): a config,
// a batch of inputs, and optionally the expected outputs of the reference implementation.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "occtrack/io/error.hpp"
#include "occtrack/projection/projector.hpp"

namespace occtrack::io {

inline constexpr const char* kProjectionCaseFormat = "occtrack.projection-case.v1";

struct ProjectionExpected {
  projection::RowMatrix<double> xi_init;  ///< B x 2n
  projection::RowMatrix<double> xi;       ///< B x 2n
  Eigen::VectorXd residual;               ///< B
};

struct ProjectionCase {
  std::string name;
  std::string description;
  projection::Settings settings;        ///< From config; batch and obstacles from the inputs' shapes.
  projection::Problem<double> problem;  ///< Sized for settings.
  std::optional<ProjectionExpected> expected;
};

/// Reads and validates a case file. Throws InputError naming the file, the key and the rule on a missing or
/// unknown key, a wrong shape, a non-finite number, a negative size or contradicting bounds.
ProjectionCase read_projection_case(const std::string& path);

/// The same from JSON text; `source` names it in messages.
ProjectionCase parse_projection_case(const std::string& text, const std::string& source);

/// {"xi_init": [[...]], "xi": [[...]], "residual": [...]} with the shapes of a case's "expected".
template <typename T>
std::string projection_result_json(const projection::Result<T>& result, int indent = -1);

/// Writes a case file (inputs and, when given, expected outputs); used to ship example problems.
std::string projection_case_json(const ProjectionCase& c, int indent = -1);

/// The projection settings as the case files' "config" object: degree, steps, horizon, iterations,
/// obstacle_radius, speed_min, speed_max, accel_max, via_steps [s1, s2], rho {...}. Datasets and models store
/// the same object in their "projection" metadata.
std::string projection_settings_json(const projection::Settings& settings);

/// Parses the object projection_settings_json writes, found at `path` of `source` (for messages). strict:
/// every key, no others (case files, datasets). Not strict: iterations and rho may be missing (their defaults
/// stay) and other keys are ignored (model metadata). Values are not validated (Settings::validate).
/// Throws InputError "SOURCE: PATH.KEY: rule".
projection::Settings parse_projection_settings(const std::string& json_text, const std::string& source,
                                               const std::string& path, bool strict);

}  // namespace occtrack::io
