// Scenario files (YAML, format tag "occtrack.scenario.v1", shared/spec/simulation.md "Scenario files"): the
// world's obstacles, the robot's start, the target's timed path and the sensor.
#pragma once

#include <string>

#include "occtrack/core/scenario.hpp"
#include "occtrack/io/error.hpp"

namespace occtrack::io {

inline constexpr const char* kScenarioFormat = "occtrack.scenario.v1";

/// Reads and validates a scenario file. Throws InputError naming the file, the key path and the rule
/// ("forest.yaml: world.obstacles[3].circle.radius: must be positive, got -0.5 (line 9)") on YAML that does
/// not parse, a wrong or missing format tag, an unknown or missing key, a value of the wrong kind or list
/// length, a non-finite number, a size that is not positive, a negative speed or noise, a target path whose
/// times do not strictly increase, an obstacle path of fewer than 2 points, an obstacle that is not exactly
/// one of `circle:` or `box:`, and a robot whose disk starts inside an obstacle.
core::Scenario read_scenario(const std::string& path);

/// The same from YAML text; `source` names it in messages.
core::Scenario parse_scenario(const std::string& yaml_text, const std::string& source);

/// Writes a scenario in the spec's layout. Numbers are written in their shortest round-trip form, so that
/// parse_scenario(scenario_yaml(s), ...) gives back exactly the same doubles.
std::string scenario_yaml(const core::Scenario& scenario);

}  // namespace occtrack::io
