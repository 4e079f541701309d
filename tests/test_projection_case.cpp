// Bad-input tests: projection case files (io::parse_projection_case / read_projection_case), the messages of
// Settings::validate(), and the input checks of Projector::solve() and its constructor. Every failure is
// checked for its message: the key path (or field) and the broken rule.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "occtrack/io/projection_case.hpp"
#include "occtrack/projection/projector.hpp"
#include "occtrack/projection/settings.hpp"

namespace {

using json = nlohmann::json;
using occtrack::io::InputError;
using occtrack::io::parse_projection_case;
using occtrack::io::ProjectionCase;
using occtrack::io::read_projection_case;
using occtrack::projection::Problem;
using occtrack::projection::Projector;
using occtrack::projection::Result;
using occtrack::projection::Settings;

const std::string kEdgeCasePath = OCCTRACK_TEST_DATA_DIR "/conformance/projection/edge_b3_o5_k10.json";
const std::string kSource = "case.json";

std::string edge_case_text() {
  static const std::string text = [] {
    std::ifstream in(kEdgeCasePath, std::ios::binary);
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
  }();
  return text;
}

json edge_case_json() {
  const std::string text = edge_case_text();
  if (text.empty()) throw std::runtime_error("cannot read " + kEdgeCasePath);
  return json::parse(text);
}

// Parses `text` and returns the InputError's message; records a test failure when something else happens.
std::string input_error_of(const std::string& text, const std::string& source = kSource) {
  try {
    (void)parse_projection_case(text, source);
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected occtrack::io::InputError, got another exception: " << e.what();
    return std::string("(wrong exception) ") + e.what();
  }
  ADD_FAILURE() << "expected occtrack::io::InputError, but the case parsed";
  return "(no exception)";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---------------------------------------------------------------------------------------------------------
// The valid file.

TEST(ProjectionCaseFile, ValidEdgeCaseParsesWithItsSizes) {
  const ProjectionCase c = parse_projection_case(edge_case_text(), kSource);
  EXPECT_EQ(c.name, "edge_b3_o5_k10");
  EXPECT_FALSE(c.description.empty());
  const Settings& s = c.settings;
  EXPECT_EQ(s.batch, 3);
  EXPECT_EQ(s.obstacles, 5);
  EXPECT_EQ(s.iterations, 10);
  EXPECT_EQ(s.degree, 10);
  EXPECT_EQ(s.steps, 100);
  EXPECT_DOUBLE_EQ(s.horizon, 5.0);
  EXPECT_EQ(s.via_step_1, 49);
  EXPECT_EQ(s.via_step_2, 74);
  EXPECT_DOUBLE_EQ(s.obstacle_radius, 0.4);
  EXPECT_DOUBLE_EQ(s.speed_min, 0.1);
  EXPECT_DOUBLE_EQ(s.speed_max, 2.0);
  EXPECT_DOUBLE_EQ(s.accel_max, 2.0);
  EXPECT_TRUE(s.validate());

  const auto& p = c.problem;
  const int n2 = 2 * s.coefficients();
  EXPECT_EQ(p.robot_velocity.rows(), 3);
  EXPECT_EQ(p.robot_velocity.cols(), 2);
  EXPECT_EQ(p.obstacles.rows(), 3);
  EXPECT_EQ(p.obstacles.cols(), 4 * 5);
  EXPECT_EQ(p.target.rows(), 3);
  EXPECT_EQ(p.target.cols(), 4);
  EXPECT_EQ(p.terminal.cols(), 4);
  EXPECT_EQ(p.via_points.cols(), 4);
  EXPECT_EQ(p.lambda0.cols(), n2);
  EXPECT_EQ(p.distance_min.cols(), 100);
  EXPECT_EQ(p.distance_max.cols(), 100);
  EXPECT_EQ(p.xi_bar.rows(), 3);
  EXPECT_EQ(p.xi_bar.cols(), n2);

  // Values land in the right place: compare a few with the JSON.
  const json doc = edge_case_json();
  EXPECT_DOUBLE_EQ(p.robot_velocity(2, 1), doc["inputs"]["robot_velocity"][2][1].get<double>());
  EXPECT_DOUBLE_EQ(p.obstacles(1, 4 * 3 + 2), doc["inputs"]["obstacles"][1][3][2].get<double>());
  EXPECT_DOUBLE_EQ(p.target(2, 3), doc["inputs"]["target"][2][3].get<double>());
  EXPECT_DOUBLE_EQ(p.distance_max(1, 99), doc["inputs"]["distance_max"][1][99].get<double>());

  ASSERT_TRUE(c.expected.has_value());
  EXPECT_EQ(c.expected->xi_init.rows(), 3);
  EXPECT_EQ(c.expected->xi_init.cols(), n2);
  EXPECT_EQ(c.expected->xi.cols(), n2);
  EXPECT_EQ(c.expected->residual.size(), 3);
  EXPECT_DOUBLE_EQ(c.expected->residual(2), doc["expected"]["residual"][2].get<double>());
}

TEST(ProjectionCaseFile, OptionalPartsMayBeLeftOut) {
  json doc = edge_case_json();
  doc.erase("expected");
  doc.erase("name");
  doc.erase("description");
  const ProjectionCase c = parse_projection_case(doc.dump(), kSource);
  EXPECT_FALSE(c.expected.has_value());
  EXPECT_TRUE(c.name.empty());
  EXPECT_EQ(c.settings.batch, 3);
}

TEST(ProjectionCaseFile, ZeroObstaclePointsIsValid) {
  json doc = edge_case_json();
  for (auto& sample : doc["inputs"]["obstacles"]) sample = json::array();
  const ProjectionCase c = parse_projection_case(doc.dump(), kSource);
  EXPECT_EQ(c.settings.obstacles, 0);
  EXPECT_EQ(c.problem.obstacles.rows(), 3);
  EXPECT_EQ(c.problem.obstacles.cols(), 0);
}

TEST(ProjectionCaseFile, WrittenCaseReadsBackTheSame) {
  const ProjectionCase c = parse_projection_case(edge_case_text(), kSource);
  const ProjectionCase back = parse_projection_case(occtrack::io::projection_case_json(c), "roundtrip.json");
  EXPECT_EQ(back.settings, c.settings);
  EXPECT_EQ(back.problem.obstacles, c.problem.obstacles);
  EXPECT_EQ(back.problem.xi_bar, c.problem.xi_bar);
  EXPECT_EQ(back.problem.distance_min, c.problem.distance_min);
  ASSERT_TRUE(back.expected.has_value());
  EXPECT_EQ(back.expected->xi, c.expected->xi);
  EXPECT_EQ(back.expected->residual, c.expected->residual);
}

TEST(ProjectionCaseFile, ReadsTheFileFromDisk) {
  const ProjectionCase c = read_projection_case(kEdgeCasePath);
  EXPECT_EQ(c.settings.batch, 3);
  EXPECT_EQ(c.settings.obstacles, 5);
  EXPECT_EQ(c.settings.iterations, 10);
}

// ---------------------------------------------------------------------------------------------------------
// Bad structured input: one mutation of the valid file each; the message must hold "case.json: KEY: " and
// the rule.

struct BadCase {
  std::string name;                      // test name suffix
  std::function<void(json&)> mutate;     // turns the valid document into a bad one
  std::string key;                       // key path the message must name
  std::string rule;                      // part of the rule the message must state
};

std::ostream& operator<<(std::ostream& out, const BadCase& c) { return out << c.name; }

class ProjectionCaseBadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(ProjectionCaseBadInput, ThrowsInputErrorNamingKeyAndRule) {
  const BadCase& bad = GetParam();
  json doc = edge_case_json();
  bad.mutate(doc);
  const std::string message = input_error_of(doc.dump());
  EXPECT_TRUE(contains(message, kSource + ": " + bad.key + ": "))
      << "message does not name the source and key \"" << bad.key << "\": " << message;
  EXPECT_TRUE(contains(message, bad.rule)) << "message does not state the rule \"" << bad.rule << "\": " << message;
}

json& config(json& d) { return d["config"]; }
json& inputs(json& d) { return d["inputs"]; }

const std::vector<BadCase> kMissingKeys = {
    {"format", [](json& d) { d.erase("format"); }, "format", "missing required key"},
    {"config", [](json& d) { d.erase("config"); }, "config", "missing required key"},
    {"inputs", [](json& d) { d.erase("inputs"); }, "inputs", "missing required key"},
    {"config_horizon", [](json& d) { config(d).erase("horizon"); }, "config.horizon", "missing required key"},
    {"config_degree", [](json& d) { config(d).erase("degree"); }, "config.degree", "missing required key"},
    {"config_via_steps", [](json& d) { config(d).erase("via_steps"); }, "config.via_steps", "missing required key"},
    {"config_rho", [](json& d) { config(d).erase("rho"); }, "config.rho", "missing required key"},
    {"config_rho_projection", [](json& d) { config(d)["rho"].erase("projection"); }, "config.rho.projection",
     "missing required key"},
    {"inputs_target", [](json& d) { inputs(d).erase("target"); }, "inputs.target", "missing required key"},
    {"inputs_robot_velocity", [](json& d) { inputs(d).erase("robot_velocity"); }, "inputs.robot_velocity",
     "missing required key"},
    {"inputs_obstacles", [](json& d) { inputs(d).erase("obstacles"); }, "inputs.obstacles", "missing required key"},
    {"inputs_xi_bar", [](json& d) { inputs(d).erase("xi_bar"); }, "inputs.xi_bar", "missing required key"},
    {"expected_xi", [](json& d) { d["expected"].erase("xi"); }, "expected.xi", "missing required key"},
    {"expected_residual", [](json& d) { d["expected"].erase("residual"); }, "expected.residual",
     "missing required key"},
};
INSTANTIATE_TEST_SUITE_P(MissingKey, ProjectionCaseBadInput, ::testing::ValuesIn(kMissingKeys),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kUnknownKeys = {
    {"top_level", [](json& d) { d["extra"] = 1; }, "extra", "unknown key"},
    {"config", [](json& d) { config(d)["batch"] = 3; }, "config.batch", "unknown key"},
    {"config_typo", [](json& d) { config(d)["horizn"] = 5.0; }, "config.horizn", "unknown key"},
    {"config_rho", [](json& d) { config(d)["rho"]["jerk"] = 1.0; }, "config.rho.jerk", "unknown key"},
    {"inputs", [](json& d) { inputs(d)["targets"] = json::array(); }, "inputs.targets", "unknown key"},
    {"expected", [](json& d) { d["expected"]["xi_final"] = json::array(); }, "expected.xi_final", "unknown key"},
};
INSTANTIATE_TEST_SUITE_P(UnknownKey, ProjectionCaseBadInput, ::testing::ValuesIn(kUnknownKeys),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kWrongShapes = {
    {"top_level_is_a_list", [](json& d) { d = json::array(); }, "(top level)", "must be an object"},
    {"config_is_a_list", [](json& d) { d["config"] = json::array(); }, "config", "must be an object"},
    {"inputs_is_a_number", [](json& d) { d["inputs"] = 3; }, "inputs", "must be an object"},
    {"expected_is_a_string", [](json& d) { d["expected"] = "none"; }, "expected", "must be an object"},
    {"target_row_with_3_numbers", [](json& d) { inputs(d)["target"][1].erase(3); }, "inputs.target[1]",
     "expected 4 numbers, got 3"},
    {"target_row_with_5_numbers", [](json& d) { inputs(d)["target"][0].push_back(1.0); }, "inputs.target[0]",
     "expected 4 numbers, got 5"},
    {"target_not_a_list", [](json& d) { inputs(d)["target"] = {{"x", 1.0}}; }, "inputs.target", "must be a list"},
    {"xi_bar_row_not_a_list", [](json& d) { inputs(d)["xi_bar"][0] = 1.0; }, "inputs.xi_bar[0]",
     "must be a list of numbers"},
    {"distance_min_wrong_batch", [](json& d) { inputs(d)["distance_min"].erase(2); }, "inputs.distance_min",
     "expected 3 samples"},
    {"terminal_extra_sample", [](json& d) { inputs(d)["terminal"].push_back(inputs(d)["terminal"][0]); },
     "inputs.terminal", "expected 3 samples"},
    {"distance_max_short_row", [](json& d) { inputs(d)["distance_max"][2].erase(99); }, "inputs.distance_max[2]",
     "expected 100 numbers, got 99"},
    {"robot_velocity_empty", [](json& d) { inputs(d)["robot_velocity"] = json::array(); }, "inputs.robot_velocity",
     "at least one sample"},
    {"obstacles_wrong_batch", [](json& d) { inputs(d)["obstacles"].erase(0); }, "inputs.obstacles",
     "must be a list of 3 samples"},
    {"obstacles_sample_with_fewer_points", [](json& d) { inputs(d)["obstacles"][2].erase(4); },
     "inputs.obstacles[2]", "expected 5 points (as in sample 0), got 4"},
    {"obstacles_sample_with_more_points",
     [](json& d) { inputs(d)["obstacles"][1].push_back(inputs(d)["obstacles"][1][0]); }, "inputs.obstacles[1]",
     "expected 5 points (as in sample 0), got 6"},
    {"obstacles_first_sample_not_a_list", [](json& d) { inputs(d)["obstacles"][0] = 0.0; }, "inputs.obstacles[0]",
     "must be a list of points"},
    {"obstacle_point_with_3_numbers", [](json& d) { inputs(d)["obstacles"][0][1].erase(3); },
     "inputs.obstacles[0][1]", "expected 4 numbers, got 3"},
    {"lambda0_short_row", [](json& d) { inputs(d)["lambda0"][0].erase(21); }, "inputs.lambda0[0]",
     "expected 22 numbers, got 21"},
    {"lambda0_long_row", [](json& d) { inputs(d)["lambda0"][1].push_back(0.0); }, "inputs.lambda0[1]",
     "expected 22 numbers, got 23"},
    {"via_steps_three_entries", [](json& d) { config(d)["via_steps"] = {10, 20, 30}; }, "config.via_steps",
     "two step indices"},
    {"via_steps_not_a_list", [](json& d) { config(d)["via_steps"] = 49; }, "config.via_steps", "two step indices"},
    {"expected_residual_wrong_length", [](json& d) { d["expected"]["residual"].erase(0); }, "expected.residual",
     "expected 3 numbers, got 2"},
    {"expected_xi_short_row", [](json& d) { d["expected"]["xi"][0].erase(0); }, "expected.xi[0]",
     "expected 22 numbers, got 21"},
};
INSTANTIATE_TEST_SUITE_P(WrongShape, ProjectionCaseBadInput, ::testing::ValuesIn(kWrongShapes),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kWrongValues = {
    {"target_nan_string", [](json& d) { inputs(d)["target"][0][0] = "nan"; }, "inputs.target[0][0]",
     "must be a number"},
    {"target_null", [](json& d) { inputs(d)["target"][2][1] = nullptr; }, "inputs.target[2][1]",
     "must be a number, got null"},
    {"obstacle_null", [](json& d) { inputs(d)["obstacles"][1][2][3] = nullptr; }, "inputs.obstacles[1][2][3]",
     "must be a number"},
    {"distance_min_inf_string", [](json& d) { inputs(d)["distance_min"][0][50] = "inf"; },
     "inputs.distance_min[0][50]", "must be a number"},
    {"expected_residual_null", [](json& d) { d["expected"]["residual"][1] = nullptr; }, "expected.residual[1]",
     "must be a number"},
    {"horizon_inf_string", [](json& d) { config(d)["horizon"] = "Infinity"; }, "config.horizon",
     "must be a number"},
    {"horizon_null", [](json& d) { config(d)["horizon"] = nullptr; }, "config.horizon", "must be a number"},
    {"rho_tracking_bool", [](json& d) { config(d)["rho"]["tracking"] = true; }, "config.rho.tracking",
     "must be a number"},
    {"steps_fraction", [](json& d) { config(d)["steps"] = 100.5; }, "config.steps", "must be an integer"},
    {"steps_string", [](json& d) { config(d)["steps"] = "100"; }, "config.steps", "must be an integer"},
    {"iterations_null", [](json& d) { config(d)["iterations"] = nullptr; }, "config.iterations",
     "must be an integer"},
    {"via_step_float", [](json& d) { config(d)["via_steps"][0] = 49.5; }, "config.via_steps[0]",
     "must be an integer"},
    {"steps_out_of_int_range", [](json& d) { config(d)["steps"] = 10000000000LL; }, "config.steps",
     "out of range"},
    {"iterations_negative_out_of_range", [](json& d) { config(d)["iterations"] = -10000000000LL; },
     "config.iterations", "out of range"},
    // 2^64 - 1 is stored as an unsigned integer; it must not wrap around to -1.
    {"steps_huge_unsigned", [](json& d) { config(d)["steps"] = std::numeric_limits<std::uint64_t>::max(); },
     "config.steps", "out of range"},
    {"name_not_a_string", [](json& d) { d["name"] = 7; }, "name", "must be a string"},
    {"description_not_a_string", [](json& d) { d["description"] = nullptr; }, "description", "must be a string"},
};
INSTANTIATE_TEST_SUITE_P(WrongValue, ProjectionCaseBadInput, ::testing::ValuesIn(kWrongValues),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kBadSizes = {
    {"steps_negative", [](json& d) { config(d)["steps"] = -5; }, "config.steps", "must be between 4 and 10000"},
    {"steps_too_small", [](json& d) { config(d)["steps"] = 3; }, "config.steps", "must be between 4 and 10000"},
    {"steps_huge", [](json& d) { config(d)["steps"] = 1000000000; }, "config.steps", "must be between 4 and 10000"},
    {"degree_negative", [](json& d) { config(d)["degree"] = -1; }, "config.degree", "must be between 5 and 30"},
    {"degree_too_small", [](json& d) { config(d)["degree"] = 4; }, "config.degree", "must be between 5 and 30"},
    {"degree_too_large", [](json& d) { config(d)["degree"] = 31; }, "config.degree", "must be between 5 and 30"},
    {"iterations_zero", [](json& d) { config(d)["iterations"] = 0; }, "config.iterations", "must be between 1 and 1000000"},
    {"iterations_negative", [](json& d) { config(d)["iterations"] = -3; }, "config.iterations",
     "must be between 1 and 1000000"},
    {"obstacle_radius_negative", [](json& d) { config(d)["obstacle_radius"] = -0.4; }, "config.obstacle_radius",
     "must be positive"},
    {"obstacle_radius_zero", [](json& d) { config(d)["obstacle_radius"] = 0.0; }, "config.obstacle_radius",
     "must be positive"},
    {"horizon_negative", [](json& d) { config(d)["horizon"] = -5.0; }, "config.horizon", "must be positive"},
    {"horizon_zero", [](json& d) { config(d)["horizon"] = 0; }, "config.horizon", "must be positive"},
    {"speed_min_negative", [](json& d) { config(d)["speed_min"] = -0.1; }, "config.speed_min",
     "must not be negative"},
    {"speed_max_zero", [](json& d) { config(d)["speed_max"] = 0.0; }, "config.speed_max", "must be positive"},
    {"accel_max_negative", [](json& d) { config(d)["accel_max"] = -2.0; }, "config.accel_max", "must be positive"},
    {"rho_obstacle_negative", [](json& d) { config(d)["rho"]["obstacle"] = -1.0; }, "config.rho.obstacle",
     "must not be negative"},
    {"rho_acceleration_negative", [](json& d) { config(d)["rho"]["acceleration"] = -0.5; },
     "config.rho.acceleration", "must not be negative"},
    {"rho_projection_zero", [](json& d) { config(d)["rho"]["projection"] = 0.0; }, "config.rho.projection",
     "must be positive"},
};
INSTANTIATE_TEST_SUITE_P(BadSize, ProjectionCaseBadInput, ::testing::ValuesIn(kBadSizes),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kContradictions = {
    {"speed_min_above_speed_max",
     [](json& d) {
       config(d)["speed_min"] = 3.0;
       config(d)["speed_max"] = 2.0;
     },
     "config.speed_min", "must not exceed speed_max"},
    {"via_steps_decreasing", [](json& d) { config(d)["via_steps"] = {74, 49}; }, "config.via_steps[1]",
     "must be greater than via_step_1"},
    {"via_steps_equal", [](json& d) { config(d)["via_steps"] = {49, 49}; }, "config.via_steps[1]",
     "must be greater than via_step_1"},
    {"via_step_1_at_start", [](json& d) { config(d)["via_steps"] = {0, 74}; }, "config.via_steps[0]",
     "strictly inside the horizon"},
    {"via_step_1_negative", [](json& d) { config(d)["via_steps"] = {-3, 74}; }, "config.via_steps[0]",
     "strictly inside the horizon"},
    {"via_step_2_at_end", [](json& d) { config(d)["via_steps"] = {49, 99}; }, "config.via_steps[1]",
     "at most steps - 2 (98)"},
    {"via_steps_beyond_horizon", [](json& d) { config(d)["via_steps"] = {120, 130}; }, "config.via_steps[0]",
     "strictly inside the horizon"},
    {"steps_shorter_than_via_steps", [](json& d) { config(d)["steps"] = 50; }, "config.via_steps[0]",
     "steps - 2 (48)"},
};
INSTANTIATE_TEST_SUITE_P(Contradiction, ProjectionCaseBadInput, ::testing::ValuesIn(kContradictions),
                         [](const auto& info) { return info.param.name; });

const std::vector<BadCase> kFormatTags = {
    {"other_version", [](json& d) { d["format"] = "occtrack.projection-case.v2"; }, "format",
     "expected \"occtrack.projection-case.v1\", got \"occtrack.projection-case.v2\""},
    {"empty", [](json& d) { d["format"] = ""; }, "format", "expected \"occtrack.projection-case.v1\""},
    {"not_a_string", [](json& d) { d["format"] = 1; }, "format", "must be a string"},
};
INSTANTIATE_TEST_SUITE_P(FormatTag, ProjectionCaseBadInput, ::testing::ValuesIn(kFormatTags),
                         [](const auto& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------------------------
// Bad text and bad files.

TEST(ProjectionCaseText, InvalidJsonNamesTheSource) {
  const std::string text = edge_case_text();
  for (const std::string& bad : {text.substr(0, text.size() / 2), std::string(), std::string("{\"format\": }"),
                                 std::string("{\"config\": {\"horizon\": NaN}}")}) {
    const std::string message = input_error_of(bad);
    EXPECT_TRUE(contains(message, kSource + ": ")) << message;
    EXPECT_TRUE(contains(message, "not valid JSON")) << message;
  }
}

// nlohmann refuses 1e400 (it would parse as inf) with json::out_of_range (406 "number overflow"), not with a
// parse_error; the reader must still turn it into an InputError that names the source and says why.
TEST(ProjectionCaseText, OverflowingNumberIsAnInputError) {
  const json probe = [] {
    try {
      return json::parse("[1e400]");
    } catch (const json::exception&) {
      return json();  // nlohmann refused it
    }
  }();
  ASSERT_TRUE(probe.is_null()) << "this nlohmann version parses 1e400 as " << probe.dump();

  json doc = edge_case_json();
  config(doc)["horizon"] = 12345.678;
  std::string text = doc.dump();
  const auto at = text.find("12345.678");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 9, "1e400");
  const std::string message = input_error_of(text);
  EXPECT_TRUE(contains(message, kSource)) << "message does not name the source: " << message;
  EXPECT_TRUE(contains(message, "finite") || contains(message, "overflow") || contains(message, "range"))
      << "message does not say the number is too large: " << message;
}

TEST(ProjectionCaseText, OverflowingNumberInInputsIsAnInputError) {
  json doc = edge_case_json();
  inputs(doc)["target"][1][2] = 12345.678;
  std::string text = doc.dump();
  text.replace(text.find("12345.678"), 9, "-1e400");
  const std::string message = input_error_of(text);
  EXPECT_TRUE(contains(message, kSource)) << message;
}

TEST(ProjectionCaseFile, MissingFileNamesThePath) {
  const std::string path = ::testing::TempDir() + "occtrack_no_such_dir/no_such_case.json";
  try {
    (void)read_projection_case(path);
    FAIL() << "read_projection_case accepted a missing file";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_TRUE(contains(message, path)) << message;
    EXPECT_TRUE(contains(message, "cannot open")) << message;
  }
}

TEST(ProjectionCaseFile, DirectoryInsteadOfFileIsAnInputError) {
  const std::string path = ::testing::TempDir();
  try {
    (void)read_projection_case(path);
    FAIL() << "read_projection_case accepted a directory";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), path)) << e.what();
  }
}

TEST(ProjectionCaseFile, ErrorsInAFileNameTheFileAndKey) {
  json doc = edge_case_json();
  inputs(doc)["target"][2].erase(0);
  const std::string path = ::testing::TempDir() + "occtrack_bad_target_case.json";
  {
    std::ofstream out(path);
    out << doc.dump(1);
  }
  try {
    (void)read_projection_case(path);
    FAIL() << "read_projection_case accepted a bad target row";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), path + ": inputs.target[2]: expected 4 numbers, got 3")) << e.what();
  }
  std::remove(path.c_str());
}

// ---------------------------------------------------------------------------------------------------------
// Settings::validate(): each rule, and its message names the field.

struct SettingsRule {
  std::string name;
  std::function<void(Settings&)> mutate;
  std::string field;  // the message starts with this
  std::string rule;   // and contains this
};

std::ostream& operator<<(std::ostream& out, const SettingsRule& r) { return out << r.name; }

class SettingsValidateMessage : public ::testing::TestWithParam<SettingsRule> {};

TEST(SettingsMessage, DefaultsAreValidAndLeaveErrorAlone) {
  const Settings s;
  std::string error = "untouched";
  EXPECT_TRUE(s.validate(&error));
  EXPECT_EQ(error, "untouched");
  EXPECT_TRUE(s.validate());
}

TEST_P(SettingsValidateMessage, NamesFieldAndRule) {
  const SettingsRule& r = GetParam();
  Settings s;
  r.mutate(s);
  std::string error;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_FALSE(s.validate(nullptr));
  EXPECT_EQ(error.rfind(r.field, 0), 0u) << "message does not start with the field \"" << r.field << "\": " << error;
  EXPECT_TRUE(contains(error, r.rule)) << "message does not state \"" << r.rule << "\": " << error;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

const std::vector<SettingsRule> kSettingsRules = {
    {"degree_low", [](Settings& s) { s.degree = 4; }, "degree (4)", "must be between 5 and 30"},
    {"degree_high", [](Settings& s) { s.degree = 31; }, "degree (31)", "must be between 5 and 30"},
    {"steps", [](Settings& s) { s.steps = 3; }, "steps (3)", "must be between 4 and 10000"},
    {"steps_too_large", [](Settings& s) { s.steps = 20000; }, "steps (20000)", "must be between 4 and 10000"},
    {"batch_too_large", [](Settings& s) { s.batch = 2000000; }, "batch (2000000)", "must be between 1 and 1000000"},
    {"horizon_nan", [](Settings& s) { s.horizon = kNaN; }, "horizon", "must be a finite number"},
    {"horizon_inf", [](Settings& s) { s.horizon = kInf; }, "horizon", "must be a finite number"},
    {"horizon_zero", [](Settings& s) { s.horizon = 0.0; }, "horizon (0)", "must be positive"},
    {"via_step_1_zero", [](Settings& s) { s.via_step_1 = 0; }, "via_step_1 (0)", "strictly inside the horizon"},
    {"via_step_1_last", [](Settings& s) { s.via_step_1 = 99; }, "via_step_1 (99)", "steps - 2 (98)"},
    {"via_step_2_before_1", [](Settings& s) { s.via_step_2 = 40; }, "via_step_2 (40)",
     "must be greater than via_step_1 (49)"},
    {"via_step_2_last", [](Settings& s) { s.via_step_2 = 99; }, "via_step_2 (99)", "at most steps - 2 (98)"},
    {"batch", [](Settings& s) { s.batch = 0; }, "batch (0)", "must be between 1 and 1000000"},
    {"obstacles", [](Settings& s) { s.obstacles = -1; }, "obstacles (-1)", "must be between 0 and 100000"},
    {"iterations", [](Settings& s) { s.iterations = 0; }, "iterations (0)", "must be between 1 and 1000000"},
    {"obstacle_radius_nan", [](Settings& s) { s.obstacle_radius = kNaN; }, "obstacle_radius",
     "must be a finite number"},
    {"obstacle_radius_zero", [](Settings& s) { s.obstacle_radius = 0.0; }, "obstacle_radius (0)",
     "must be positive"},
    {"speed_min_nan", [](Settings& s) { s.speed_min = kNaN; }, "speed_min", "must be a finite number"},
    {"speed_max_inf", [](Settings& s) { s.speed_max = kInf; }, "speed_max", "must be a finite number"},
    {"speed_min_negative", [](Settings& s) { s.speed_min = -0.5; }, "speed_min (-0.5)", "must not be negative"},
    {"speed_max_zero", [](Settings& s) { s.speed_max = 0.0; }, "speed_max (0)", "must be positive"},
    {"speed_min_above_max",
     [](Settings& s) {
       s.speed_min = 3.0;
       s.speed_max = 2.0;
     },
     "speed_min (3)", "must not exceed speed_max (2)"},
    {"accel_max_nan", [](Settings& s) { s.accel_max = kNaN; }, "accel_max", "must be a finite number"},
    {"accel_max_zero", [](Settings& s) { s.accel_max = 0.0; }, "accel_max (0)", "must be positive"},
    {"rho_obstacle_nan", [](Settings& s) { s.rho.obstacle = kNaN; }, "rho.obstacle", "must be a finite number"},
    {"rho_obstacle_negative", [](Settings& s) { s.rho.obstacle = -1.0; }, "rho.obstacle (-1)",
     "must not be negative"},
    {"rho_velocity_negative", [](Settings& s) { s.rho.velocity = -1.0; }, "rho.velocity (-1)",
     "must not be negative"},
    {"rho_acceleration_inf", [](Settings& s) { s.rho.acceleration = kInf; }, "rho.acceleration",
     "must be a finite number"},
    {"rho_tracking_negative", [](Settings& s) { s.rho.tracking = -2.0; }, "rho.tracking (-2)",
     "must not be negative"},
    {"rho_projection_negative", [](Settings& s) { s.rho.projection = -1.0; }, "rho.projection (-1)",
     "must not be negative"},
    {"rho_projection_zero", [](Settings& s) { s.rho.projection = 0.0; }, "rho.projection (0)", "must be positive"},
    {"threads", [](Settings& s) { s.threads = 0; }, "threads (0)", "must be between 1 and 1024"},
};
INSTANTIATE_TEST_SUITE_P(Rule, SettingsValidateMessage, ::testing::ValuesIn(kSettingsRules),
                         [](const auto& info) { return info.param.name; });

TEST(SettingsMessage, ReportsTheFirstBrokenRule) {
  Settings s;
  s.degree = 2;
  s.threads = 0;
  std::string error;
  EXPECT_FALSE(s.validate(&error));
  EXPECT_EQ(error.rfind("degree", 0), 0u) << error;
  EXPECT_FALSE(contains(error, "threads")) << error;
}

TEST(SettingsMessage, ZeroWeightsOtherThanProjectionAreValid) {
  Settings s;
  s.rho.obstacle = s.rho.velocity = s.rho.acceleration = s.rho.tracking = 0.0;
  s.obstacles = 0;
  s.speed_min = 0.0;
  std::string error;
  EXPECT_TRUE(s.validate(&error)) << error;
}

// ---------------------------------------------------------------------------------------------------------
// Projector: the constructor refuses invalid settings; solve() refuses misshapen or non-finite input.

class ProjectorInputCheck : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = parse_projection_case(edge_case_text(), kSource);
    projector_ = std::make_unique<Projector<double>>(c_.settings);
    problem_ = c_.problem;
    result_ = projector_->make_result();
  }

  // Expects solve() and check() to refuse, with a message holding every part; the result stays untouched.
  void expect_refused(const std::vector<std::string>& parts) {
    result_.xi.setConstant(7.0);
    result_.xi_init.setConstant(7.0);
    const Result<double> before = result_;
    std::string error;
    EXPECT_FALSE(projector_->solve(problem_, result_, &error));
    for (const std::string& part : parts) EXPECT_TRUE(contains(error, part)) << "\"" << part << "\" not in: " << error;
    if (result_.xi.rows() == before.xi.rows() && result_.xi.cols() == before.xi.cols()) {
      EXPECT_EQ(result_.xi, before.xi) << "solve() changed the result although it refused the input";
    }
    EXPECT_FALSE(projector_->solve(problem_, result_, nullptr));
  }

  ProjectionCase c_;
  std::unique_ptr<Projector<double>> projector_;
  Problem<double> problem_;
  Result<double> result_;
};

TEST_F(ProjectorInputCheck, ValidProblemSolves) {
  std::string error;
  EXPECT_TRUE(projector_->check(problem_, &error)) << error;
  EXPECT_TRUE(projector_->solve(problem_, result_, &error)) << error;
  EXPECT_TRUE(error.empty()) << error;
  EXPECT_TRUE(result_.xi.allFinite());
}

TEST_F(ProjectorInputCheck, TargetWithWrongColumns) {
  problem_.target.conservativeResize(3, 3);
  expect_refused({"target", "3 x 3", "expected 3 x 4"});
  std::string error;
  EXPECT_FALSE(projector_->check(problem_, &error));
  EXPECT_TRUE(contains(error, "target")) << error;
}

TEST_F(ProjectorInputCheck, TargetWithWrongRows) {
  problem_.target.conservativeResize(2, 4);
  expect_refused({"target", "2 x 4", "expected 3 x 4"});
}

TEST_F(ProjectorInputCheck, LambdaWithWrongColumns) {
  problem_.lambda0.conservativeResize(3, 20);
  expect_refused({"lambda0", "expected 3 x 22"});
}

TEST_F(ProjectorInputCheck, ObstaclesWithWrongPointCount) {
  problem_.obstacles.conservativeResize(3, 16);
  expect_refused({"obstacles", "expected 3 x 20"});
}

TEST_F(ProjectorInputCheck, NanInObstacles) {
  problem_.obstacles(1, 6) = std::numeric_limits<double>::quiet_NaN();
  expect_refused({"obstacles", "sample 1", "column 6", "not finite"});
}

TEST_F(ProjectorInputCheck, InfInXiBar) {
  problem_.xi_bar(2, 0) = -std::numeric_limits<double>::infinity();
  expect_refused({"xi_bar", "sample 2", "column 0", "not finite"});
}

TEST_F(ProjectorInputCheck, NanInDistanceMax) {
  problem_.distance_max(0, 99) = std::numeric_limits<double>::quiet_NaN();
  expect_refused({"distance_max", "sample 0", "column 99", "not finite"});
}

TEST_F(ProjectorInputCheck, ResultXiWithWrongSize) {
  result_.xi.resize(3, 21);
  std::string error;
  EXPECT_FALSE(projector_->solve(problem_, result_, &error));
  EXPECT_TRUE(contains(error, "result.xi ")) << error;
  EXPECT_TRUE(contains(error, "expected 3 x 22")) << error;
}

TEST_F(ProjectorInputCheck, ResultXiInitWithWrongSize) {
  result_.xi_init.resize(2, 22);
  std::string error;
  EXPECT_FALSE(projector_->solve(problem_, result_, &error));
  EXPECT_TRUE(contains(error, "result.xi_init")) << error;
}

TEST_F(ProjectorInputCheck, ResultResidualWithWrongSize) {
  result_.residual.resize(2);
  std::string error;
  EXPECT_FALSE(projector_->solve(problem_, result_, &error));
  EXPECT_TRUE(contains(error, "result.residual")) << error;
  EXPECT_TRUE(contains(error, "expected 3 x 1")) << error;
}

TEST_F(ProjectorInputCheck, ResultResidualHistoryWithoutRecording) {
  result_.residual_history.resize(3, 10);
  std::string error;
  EXPECT_FALSE(projector_->solve(problem_, result_, &error));
  EXPECT_TRUE(contains(error, "result.residual_history")) << error;
}

TEST(ProjectorInputCheckFloat, ValueBeyondFloatRangeIsRefused) {
  const ProjectionCase c = parse_projection_case(edge_case_text(), kSource);
  Projector<float> projector(c.settings);
  Problem<float> problem = projector.make_problem();
  problem.target = c.problem.target.cast<float>();
  problem.target(1, 2) = static_cast<float>(1e39);  // inf in float
  Result<float> result = projector.make_result();
  std::string error;
  EXPECT_FALSE(projector.solve(problem, result, &error));
  EXPECT_TRUE(contains(error, "target")) << error;
  EXPECT_TRUE(contains(error, "not finite")) << error;
}

std::string constructor_error(const Settings& s) {
  try {
    Projector<double> projector(s);
  } catch (const std::invalid_argument& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected std::invalid_argument, got: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "the Projector constructor accepted invalid settings";
  return "";
}

TEST(ProjectorConstructorMessage, ThrowsInvalidArgumentWithTheValidateMessage) {
  Settings s;
  s.speed_min = 3.0;
  s.speed_max = 2.0;
  std::string expected;
  ASSERT_FALSE(s.validate(&expected));
  const std::string message = constructor_error(s);
  EXPECT_TRUE(contains(message, expected)) << message;
  EXPECT_TRUE(contains(message, "speed_min")) << message;
}

TEST(ProjectorConstructorMessage, NamesEachBrokenField) {
  {
    Settings s;
    s.threads = 0;
    EXPECT_TRUE(contains(constructor_error(s), "threads")) << constructor_error(s);
  }
  {
    Settings s;
    s.degree = 40;
    EXPECT_TRUE(contains(constructor_error(s), "degree")) << constructor_error(s);
  }
  {
    Settings s;
    s.rho.projection = 0.0;
    EXPECT_TRUE(contains(constructor_error(s), "rho.projection")) << constructor_error(s);
  }
  {
    Settings s;
    s.batch = 0;
    EXPECT_TRUE(contains(constructor_error(s), "batch")) << constructor_error(s);
  }
}

}  // namespace
