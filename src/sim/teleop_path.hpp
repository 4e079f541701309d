// Tele-operated target paths (TargetMotion::teleop of include/occtrack/sim/scenario_generator.hpp), private to
// the scenario generator: generate_episode (src/sim/target_path.cpp) hands teleop settings here.
#pragma once

#include <cstdint>
#include <string>

#include "occtrack/core/scenario.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace occtrack::sim::generator {

/// generate_episode for motion teleop; `target` is already validated.
core::Scenario generate_teleop_episode(const core::Scenario& world, const TargetSettings& target, std::uint64_t seed,
                                       const std::string& name);

}  // namespace occtrack::sim::generator
