// Scenario files (io/scenario.hpp): the spec's example parses to the right values, defaults apply, writing
// and reading back gives the same doubles, the shipped example loads, and every kind of bad input is an
// InputError whose message names the file, the key path and the rule.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "occtrack/io/scenario.hpp"

namespace {

using occtrack::core::ObstacleSpec;
using occtrack::core::Scenario;
using occtrack::core::Vec2;
using occtrack::io::InputError;
using occtrack::io::parse_scenario;
using occtrack::io::read_scenario;
using occtrack::io::scenario_yaml;

const std::string kSource = "forest.yaml";

// The example of shared/spec/simulation.md, "Scenario files".
const std::string kExample = R"(format: occtrack.scenario.v1
name: forest-a-3
duration: 150.0                  # simulated seconds
world:
  obstacles:
    - circle: {center: [4.0, 2.5], radius: 0.6}
    - box: {center: [-3.0, 7.0], size: [2.0, 0.5], yaw: 0.4}
    - circle: {center: [0.0, -6.0], radius: 0.5, path: [[0, -6], [6, -6]], speed: 0.7}   # moves, back and forth
robot: {position: [0.0, -2.0], velocity: [0.0, 0.0], radius: 0.25}
target:
  radius: 0.25
  trajectory:                    # timed waypoints [t, x, y], linear between them, held after the last
    - [0.0, 0.0, 0.0]
    - [2.0, 1.5, 0.5]
sensor: {beams: 720, range: 10.0, noise: 0.0}        # optional; these are the defaults
)";

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The example with one piece of text replaced (which must occur exactly once).
std::string with(const std::string& from, const std::string& to) {
  const std::size_t at = kExample.find(from);
  EXPECT_NE(at, std::string::npos) << "not in the example: " << from;
  EXPECT_EQ(kExample.find(from, at + 1), std::string::npos) << "twice in the example: " << from;
  if (at == std::string::npos) return kExample;
  std::string text = kExample;
  text.replace(at, from.size(), to);
  return text;
}

// Parses `text` and returns the InputError's message; records a failure when something else happens.
std::string error_of(const std::string& text) {
  try {
    (void)parse_scenario(text, kSource);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected occtrack::io::InputError, got another exception: " << e.what();
    return std::string("(wrong exception) ") + e.what();
  }
  ADD_FAILURE() << "expected occtrack::io::InputError, but the scenario parsed";
  return "(no exception)";
}

// The message starts with the file and the key path, and states the rule.
#define EXPECT_INPUT_ERROR(text, key_path, rule)                                             \
  do {                                                                                       \
    const std::string message_ = error_of(text);                                             \
    EXPECT_TRUE(contains(message_, kSource + ": " + std::string(key_path) + ": ")) << message_; \
    EXPECT_TRUE(contains(message_, rule)) << message_;                                       \
  } while (false)

void expect_same(const Scenario& a, const Scenario& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.duration, b.duration);
  ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
  for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
    const ObstacleSpec &p = a.obstacles[i], &q = b.obstacles[i];
    EXPECT_EQ(p.shape, q.shape) << i;
    EXPECT_EQ(p.center, q.center) << i;
    EXPECT_EQ(p.radius, q.radius) << i;
    EXPECT_EQ(p.size, q.size) << i;
    EXPECT_EQ(p.yaw, q.yaw) << i;
    EXPECT_EQ(p.path, q.path) << i;
    EXPECT_EQ(p.speed, q.speed) << i;
  }
  EXPECT_EQ(a.robot_position, b.robot_position);
  EXPECT_EQ(a.robot_velocity, b.robot_velocity);
  EXPECT_EQ(a.robot_radius, b.robot_radius);
  EXPECT_EQ(a.target_radius, b.target_radius);
  ASSERT_EQ(a.target.size(), b.target.size());
  for (std::size_t i = 0; i < a.target.size(); ++i) {
    EXPECT_EQ(a.target[i].time, b.target[i].time) << i;
    EXPECT_EQ(a.target[i].position, b.target[i].position) << i;
  }
  EXPECT_EQ(a.sensor.beams, b.sensor.beams);
  EXPECT_EQ(a.sensor.range, b.sensor.range);
  EXPECT_EQ(a.sensor.noise, b.sensor.noise);
}

// ---------------------------------------------------------------------------------------------------------
// Valid files.

TEST(ScenarioFile, SpecExampleParsesWithItsValues) {
  const Scenario s = parse_scenario(kExample, kSource);
  EXPECT_EQ(s.name, "forest-a-3");
  EXPECT_EQ(s.duration, 150.0);
  ASSERT_EQ(s.obstacles.size(), 3u);
  EXPECT_EQ(s.obstacles[0].shape, ObstacleSpec::Shape::circle);
  EXPECT_EQ(s.obstacles[0].center, Vec2(4.0, 2.5));
  EXPECT_EQ(s.obstacles[0].radius, 0.6);
  EXPECT_FALSE(s.obstacles[0].moving());
  EXPECT_EQ(s.obstacles[1].shape, ObstacleSpec::Shape::box);
  EXPECT_EQ(s.obstacles[1].center, Vec2(-3.0, 7.0));
  EXPECT_EQ(s.obstacles[1].size, Vec2(2.0, 0.5));
  EXPECT_EQ(s.obstacles[1].yaw, 0.4);
  EXPECT_EQ(s.obstacles[2].shape, ObstacleSpec::Shape::circle);
  EXPECT_EQ(s.obstacles[2].center, Vec2(0.0, -6.0));
  EXPECT_EQ(s.obstacles[2].radius, 0.5);
  ASSERT_EQ(s.obstacles[2].path.size(), 2u);
  EXPECT_EQ(s.obstacles[2].path[0], Vec2(0.0, -6.0));
  EXPECT_EQ(s.obstacles[2].path[1], Vec2(6.0, -6.0));
  EXPECT_EQ(s.obstacles[2].speed, 0.7);
  EXPECT_TRUE(s.obstacles[2].moving());
  EXPECT_EQ(s.robot_position, Vec2(0.0, -2.0));
  EXPECT_EQ(s.robot_velocity, Vec2(0.0, 0.0));
  EXPECT_EQ(s.robot_radius, 0.25);
  EXPECT_EQ(s.target_radius, 0.25);
  ASSERT_EQ(s.target.size(), 2u);
  EXPECT_EQ(s.target[0].time, 0.0);
  EXPECT_EQ(s.target[0].position, Vec2(0.0, 0.0));
  EXPECT_EQ(s.target[1].time, 2.0);
  EXPECT_EQ(s.target[1].position, Vec2(1.5, 0.5));
  EXPECT_EQ(s.sensor.beams, 720);
  EXPECT_EQ(s.sensor.range, 10.0);
  EXPECT_EQ(s.sensor.noise, 0.0);
}

TEST(ScenarioFile, OptionalKeysTakeTheirDefaults) {
  const Scenario s = parse_scenario(R"(format: occtrack.scenario.v1
name: bare
duration: 5
world: {obstacles: []}
robot: {position: [1, 2]}
target: {trajectory: [[0, 3, 4]]}
)",
                                    kSource);
  EXPECT_TRUE(s.obstacles.empty());
  EXPECT_EQ(s.duration, 5.0);
  EXPECT_EQ(s.robot_position, Vec2(1.0, 2.0));
  EXPECT_EQ(s.robot_velocity, Vec2(0.0, 0.0));
  EXPECT_EQ(s.robot_radius, 0.25);
  EXPECT_EQ(s.target_radius, 0.25);
  ASSERT_EQ(s.target.size(), 1u);
  EXPECT_EQ(s.sensor.beams, 720);
  EXPECT_EQ(s.sensor.range, 10.0);
  EXPECT_EQ(s.sensor.noise, 0.0);

  // A partial sensor map keeps the other defaults; a box's yaw defaults to 0.
  const Scenario t = parse_scenario(with("sensor: {beams: 720, range: 10.0, noise: 0.0}", "sensor: {noise: 0.02}")
                                        .replace(kExample.find("yaw: 0.4") - 2, 10, ""),
                                    kSource);
  EXPECT_EQ(t.sensor.beams, 720);
  EXPECT_EQ(t.sensor.range, 10.0);
  EXPECT_EQ(t.sensor.noise, 0.02);
  EXPECT_EQ(t.obstacles[1].yaw, 0.0);
}

TEST(ScenarioFile, WriteThenReadGivesTheSameDoubles) {
  const Scenario example = parse_scenario(kExample, kSource);
  const std::string text = scenario_yaml(example);
  EXPECT_TRUE(contains(text, "format: occtrack.scenario.v1\n")) << text;
  EXPECT_TRUE(contains(text, "- circle: {center: [4.0, 2.5], radius: 0.6}")) << text;
  expect_same(parse_scenario(text, "written.yaml"), example);

  // Doubles that need all 17 digits, tiny and huge magnitudes, negative zero, and an awkward name.
  Scenario s = example;
  s.name = "odd name: \"quoted\" # not a comment";
  s.duration = 0.1 + 0.2;
  s.obstacles[0].center = Vec2(1.0 / 3.0, -2.0 / 7.0);
  s.obstacles[0].radius = 1e-300;
  s.obstacles[1].yaw = -0.0;
  s.obstacles[1].size = Vec2(std::nextafter(1.0, 2.0), 123456789.123456789);
  s.obstacles[2].path = {Vec2(0.0, -6.0), Vec2(std::sqrt(2.0), -6.0), Vec2(6.0, 1e10)};
  s.obstacles[2].speed = 0.0;  // a path at zero speed stays written and read
  s.robot_position = Vec2(-1e-5, 12.5);
  s.robot_velocity = Vec2(0.7, -1.0 / 9.0);
  s.target.push_back({2.0 + 1e-15, Vec2(std::exp(1.0), -std::numbers::pi)});
  s.sensor = {1, 3.3, 0.05};
  const Scenario back = parse_scenario(scenario_yaml(s), "written.yaml");
  expect_same(back, s);
  EXPECT_TRUE(std::signbit(back.obstacles[1].yaw));

  // Names that YAML would read as something else are quoted.
  for (const std::string name : {"null", "~", "true", "123", "-x", "a b", "ünï"}) {
    s.name = name;
    EXPECT_EQ(parse_scenario(scenario_yaml(s), "written.yaml").name, name);
  }
  Scenario empty_world = example;
  empty_world.obstacles.clear();
  expect_same(parse_scenario(scenario_yaml(empty_world), "written.yaml"), empty_world);
}

TEST(ScenarioFile, ShippedExampleLoads) {
  const std::string path = OCCTRACK_TEST_DATA_DIR "/scenarios/example.yaml";
  expect_same(read_scenario(path), parse_scenario(kExample, kSource));
}

TEST(ScenarioFile, MissingFileNamesThePath) {
  try {
    (void)read_scenario("/nonexistent/scenario.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "/nonexistent/scenario.yaml")) << e.what();
    EXPECT_TRUE(contains(e.what(), "cannot open")) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------------------
// Bad input: one test per kind, each checking the key path and the rule.

TEST(ScenarioFileErrors, NotYamlNamesTheLine) {
  const std::string message = error_of(with("robot: {position: [0.0, -2.0],", "robot: {position: [0.0, -2.0"));
  EXPECT_TRUE(contains(message, kSource + ": line ")) << message;
  EXPECT_TRUE(contains(message, "not valid YAML")) << message;
  // An unclosed flow map on line 7.
  const std::string unclosed = error_of(with("yaw: 0.4}", "yaw: 0.4"));
  EXPECT_TRUE(contains(unclosed, kSource + ": line ")) << unclosed;
  EXPECT_TRUE(contains(unclosed, "not valid YAML")) << unclosed;
  EXPECT_INPUT_ERROR("", "(top level)", "empty");
  EXPECT_INPUT_ERROR(kExample + "---\n" + kExample, "line 16, column 1", "expected one YAML document");
  // yaml-cpp 0.7's LoadAll loops for ever on a leading ',' (and Load reads it as null): a named error instead.
  EXPECT_INPUT_ERROR("," + kExample, "line 1, column 1", "not valid YAML");
  EXPECT_INPUT_ERROR("[1, 2]", "(top level)", "must be a map");
}

TEST(ScenarioFileErrors, FormatTag) {
  EXPECT_INPUT_ERROR(with("format: occtrack.scenario.v1\n", ""), "format", "missing required key");
  EXPECT_INPUT_ERROR(with("occtrack.scenario.v1", "occtrack.scenario.v2"), "format",
                     "expected occtrack.scenario.v1, got occtrack.scenario.v2");
}

TEST(ScenarioFileErrors, UnknownKeys) {
  EXPECT_INPUT_ERROR(kExample + "colour: red\n", "colour", "unknown key");
  EXPECT_INPUT_ERROR(with("yaw: 0.4}", "yaw: 0.4, colour: red}"), "world.obstacles[1].box.colour", "unknown key");
  EXPECT_INPUT_ERROR(with("radius: 0.6}", "radius: 0.6, yaw: 1}"), "world.obstacles[0].circle.yaw", "unknown key");
  EXPECT_INPUT_ERROR(with("radius: 0.25}", "radius: 0.25, heading: 0}"), "robot.heading", "unknown key");
  EXPECT_INPUT_ERROR(with("noise: 0.0}", "noise: 0.0, fov: 3}"), "sensor.fov", "unknown key");
  EXPECT_INPUT_ERROR(with("world:\n", "world:\n  walls: []\n"), "world.walls", "unknown key");
  EXPECT_INPUT_ERROR(with("  radius: 0.25\n", "  radius: 0.25\n  speed: 1\n"), "target.speed", "unknown key");
  // The message lists what is allowed, and a repeated key is an error too.
  EXPECT_TRUE(contains(error_of(kExample + "colour: red\n"), "expected one of: format, name, duration"));
  EXPECT_INPUT_ERROR(kExample + "duration: 20\n", "duration", "key given twice");
}

TEST(ScenarioFileErrors, MissingRequiredKeys) {
  EXPECT_INPUT_ERROR(with("name: forest-a-3\n", ""), "name", "missing required key");
  EXPECT_INPUT_ERROR(with("duration: 150.0 ", "# "), "duration", "missing required key");
  EXPECT_INPUT_ERROR(with("robot: {position: [0.0, -2.0], ", "robot: {"), "robot.position", "missing required key");
  EXPECT_INPUT_ERROR(with("center: [4.0, 2.5], ", ""), "world.obstacles[0].circle.center", "missing required key");
  EXPECT_INPUT_ERROR(with(", radius: 0.6", ""), "world.obstacles[0].circle.radius", "missing required key");
  EXPECT_INPUT_ERROR(with("size: [2.0, 0.5], ", ""), "world.obstacles[1].box.size", "missing required key");
  const std::string no_trajectory = kExample.substr(0, kExample.find("  trajectory:")) +
                                    kExample.substr(kExample.find("sensor:"));
  EXPECT_INPUT_ERROR(no_trajectory, "target.trajectory", "missing required key");
  const std::string no_world = kExample.substr(0, kExample.find("world:")) + kExample.substr(kExample.find("robot:"));
  EXPECT_INPUT_ERROR(no_world, "world", "missing required key");
  EXPECT_INPUT_ERROR(no_world + "world: {}\n", "world.obstacles", "missing required key");
  EXPECT_INPUT_ERROR(no_world + "world: {obstacles: }\n", "world.obstacles", "must be a list");
  const std::string no_target =
      kExample.substr(0, kExample.find("target:")) + kExample.substr(kExample.find("sensor:"));
  EXPECT_INPUT_ERROR(no_target, "target", "missing required key");
  EXPECT_INPUT_ERROR(with("\nrobot: {position: [0.0, -2.0], velocity: [0.0, 0.0], radius: 0.25}", ""), "robot",
                     "missing required key");
}

TEST(ScenarioFileErrors, NonFiniteAndNonNumbers) {
  EXPECT_INPUT_ERROR(with("duration: 150.0", "duration: .inf"), "duration", "must be a finite number");
  EXPECT_INPUT_ERROR(with("radius: 0.6", "radius: .nan"), "world.obstacles[0].circle.radius",
                     "must be a finite number");
  EXPECT_INPUT_ERROR(with("center: [4.0, 2.5]", "center: [1e400, 2.5]"), "world.obstacles[0].circle.center[0]",
                     "must be a finite number");
  EXPECT_INPUT_ERROR(with("[2.0, 1.5, 0.5]", "[2.0, -.inf, 0.5]"), "target.trajectory[1][1]",
                     "must be a finite number");
  EXPECT_INPUT_ERROR(with("yaw: 0.4", "yaw: abc"), "world.obstacles[1].box.yaw", "must be a number, got abc");
  EXPECT_INPUT_ERROR(with("radius: 0.6", "radius: \"0.6\""), "world.obstacles[0].circle.radius",
                     "must be a number, got the string \"0.6\"");
  EXPECT_INPUT_ERROR(with("range: 10.0", "range: [10]"), "sensor.range", "must be a number, got a list of 1");
  EXPECT_INPUT_ERROR(with("speed: 0.7", "speed: "), "world.obstacles[2].circle.speed", "must be a number, got null");
  EXPECT_INPUT_ERROR(with("beams: 720", "beams: 720.5"), "sensor.beams", "must be an integer");
}

TEST(ScenarioFileErrors, SizesMustBePositive) {
  EXPECT_INPUT_ERROR(with("radius: 0.6", "radius: -0.6"), "world.obstacles[0].circle.radius",
                     "must be positive, got -0.6");
  EXPECT_INPUT_ERROR(with("radius: 0.6", "radius: 0"), "world.obstacles[0].circle.radius", "must be positive");
  EXPECT_INPUT_ERROR(with("size: [2.0, 0.5]", "size: [2.0, 0]"), "world.obstacles[1].box.size[1]", "must be positive");
  EXPECT_INPUT_ERROR(with("size: [2.0, 0.5]", "size: [-2.0, 0.5]"), "world.obstacles[1].box.size[0]",
                     "must be positive");
  EXPECT_INPUT_ERROR(with("duration: 150.0", "duration: 0"), "duration", "must be positive");
  EXPECT_INPUT_ERROR(with("range: 10.0", "range: -10"), "sensor.range", "must be positive");
  EXPECT_INPUT_ERROR(with("beams: 720", "beams: 0"), "sensor.beams", "must be at least 1");
  EXPECT_INPUT_ERROR(with("beams: 720", "beams: 1000000000000"), "sensor.beams", "out of range");
  EXPECT_INPUT_ERROR(with("beams: 720", "beams: 100000000"), "sensor.beams", "must be at most");
  EXPECT_INPUT_ERROR(with("velocity: [0.0, 0.0], radius: 0.25", "velocity: [0.0, 0.0], radius: 0"), "robot.radius",
                     "must be positive");
  EXPECT_INPUT_ERROR(with("  radius: 0.25\n", "  radius: -0.25\n"), "target.radius", "must be positive");
}

TEST(ScenarioFileErrors, NegativeNoiseAndSpeed) {
  EXPECT_INPUT_ERROR(with("noise: 0.0", "noise: -0.1"), "sensor.noise", "must not be negative, got -0.1");
  EXPECT_INPUT_ERROR(with("speed: 0.7", "speed: -0.7"), "world.obstacles[2].circle.speed",
                     "must not be negative, got -0.7");
}

TEST(ScenarioFileErrors, TargetTimesMustStrictlyIncrease) {
  EXPECT_INPUT_ERROR(with("[2.0, 1.5, 0.5]", "[0.0, 1.5, 0.5]"), "target.trajectory[1]",
                     "times must be strictly increasing, got t = 0.0 after t = 0.0");
  EXPECT_INPUT_ERROR(with("[2.0, 1.5, 0.5]", "[2.0, 1.5, 0.5]\n    - [1.0, 2.0, 2.0]"), "target.trajectory[2]",
                     "times must be strictly increasing");
  EXPECT_INPUT_ERROR(with("    - [0.0, 0.0, 0.0]\n    - [2.0, 1.5, 0.5]\n", "    []\n"), "target.trajectory",
                     "needs at least one");
}

TEST(ScenarioFileErrors, ObstaclePathNeedsTwoPointsAndASpeed) {
  EXPECT_INPUT_ERROR(with("path: [[0, -6], [6, -6]]", "path: [[0, -6]]"), "world.obstacles[2].circle.path",
                     "needs at least 2 points, got 1");
  EXPECT_INPUT_ERROR(with("path: [[0, -6], [6, -6]]", "path: []"), "world.obstacles[2].circle.path",
                     "needs at least 2 points, got 0");
  EXPECT_INPUT_ERROR(with(", speed: 0.7", ""), "world.obstacles[2].circle.speed", "missing required key");
  EXPECT_INPUT_ERROR(with("path: [[0, -6], [6, -6]], ", ""), "world.obstacles[2].circle.speed", "without a path");
}

TEST(ScenarioFileErrors, WrongListLengths) {
  EXPECT_INPUT_ERROR(with("position: [0.0, -2.0]", "position: [0.0, -2.0, 1.0]"), "robot.position",
                     "expected 2 numbers [x, y], got 3");
  EXPECT_INPUT_ERROR(with("velocity: [0.0, 0.0]", "velocity: [0.0]"), "robot.velocity", "expected 2 numbers");
  EXPECT_INPUT_ERROR(with("center: [-3.0, 7.0]", "center: -3.0"), "world.obstacles[1].box.center", "must be a list");
  EXPECT_INPUT_ERROR(with("size: [2.0, 0.5]", "size: [2.0, 0.5, 1.0]"), "world.obstacles[1].box.size",
                     "expected 2 numbers");
  EXPECT_INPUT_ERROR(with("[[0, -6], [6, -6]]", "[[0, -6], [6]]"), "world.obstacles[2].circle.path[1]",
                     "expected 2 numbers");
  EXPECT_INPUT_ERROR(with("[2.0, 1.5, 0.5]", "[2.0, 1.5]"), "target.trajectory[1]",
                     "expected 3 numbers [t, x, y], got 2");
  EXPECT_INPUT_ERROR(with("[0.0, 0.0, 0.0]", "[0.0, 0.0, 0.0, 0.0]"), "target.trajectory[0]", "expected 3 numbers");
}

TEST(ScenarioFileErrors, ObstacleIsExactlyOneShape) {
  EXPECT_INPUT_ERROR(with("- circle: {center: [4.0, 2.5], radius: 0.6}",
                          "- {circle: {center: [4.0, 2.5], radius: 0.6}, box: {center: [0, 0], size: [1, 1]}}"),
                     "world.obstacles[0]", "must be exactly one of `circle:` or `box:`, got 2 keys (circle, box)");
  EXPECT_INPUT_ERROR(with("- circle: {center: [4.0, 2.5], radius: 0.6}", "- {}"), "world.obstacles[0]",
                     "must be exactly one of `circle:` or `box:`, got 0 keys");
  EXPECT_INPUT_ERROR(with("- box: {", "- polygon: {"), "world.obstacles[1].polygon", "unknown shape");
  EXPECT_INPUT_ERROR(with("- circle: {center: [4.0, 2.5], radius: 0.6}", "- [4.0, 2.5]"), "world.obstacles[0]",
                     "must be a map");
  EXPECT_INPUT_ERROR(with("- circle: {center: [4.0, 2.5], radius: 0.6}", "- circle: 0.6"),
                     "world.obstacles[0].circle", "must be a map");
}

TEST(ScenarioFileErrors, RobotStartingInsideAnObstacle) {
  // Centre inside obstacle 1 (the box about (-3, 7)).
  EXPECT_INPUT_ERROR(with("position: [0.0, -2.0]", "position: [-3.0, 7.1]"), "robot.position",
                     "starts inside world.obstacles[1]");
  // Centre outside circle 0 (radius 0.6) but the robot's disk (radius 0.25) overlaps it.
  EXPECT_INPUT_ERROR(with("position: [0.0, -2.0]", "position: [4.0, 3.2]"), "robot.position",
                     "starts inside world.obstacles[0]");
  // Touching is allowed: 0.5 + 0.25 from the centre of a circle of radius 0.5 (exact in binary).
  std::string touching = with("position: [0.0, -2.0]", "position: [4.75, 2.5]");
  touching.replace(touching.find("radius: 0.6"), 11, "radius: 0.5");
  EXPECT_NO_THROW((void)parse_scenario(touching, kSource));
}

TEST(ScenarioFileErrors, MessagesNameTheLine) {
  const std::string message = error_of(with("radius: 0.6", "radius: -0.6"));
  EXPECT_TRUE(contains(message, "(line 6)")) << message;
}

}  // namespace
