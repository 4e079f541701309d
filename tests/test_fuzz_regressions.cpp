// Inputs the fuzzers of fuzz/ found (or that were built to reproduce what they pointed at), fed through the
// normal API: each must read, or be refused with an io::InputError naming the file; never a crash, a stray
// exception type or an absurd allocation. Saved inputs live in tests/data/fuzz/regressions/ as
// <target>-<short>.bin (fuzz/README.md, "Adding a regression"); inputs too large to keep are built here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/error.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/target_path.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/sim/recorded_path.hpp"

namespace occtrack {
namespace {

namespace fs = std::filesystem;

const fs::path kRegressions = fs::path(OCCTRACK_TEST_DATA_DIR) / "fuzz" / "regressions";

std::vector<fs::path> saved_inputs() {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(kRegressions))
    if (entry.path().extension() == ".bin") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// Reads `path` the way the fuzz target named by the file's prefix does, through the public entry points.
void read_as_target(const fs::path& path) {
  const std::string name = path.filename().string(), file = path.string();
  auto is = [&](const std::string& target) { return name.rfind(target + "-", 0) == 0; };
  if (is("scenario")) {
    io::read_scenario(file);
  } else if (is("projection_case")) {
    io::read_projection_case(file);
  } else if (is("safetensors")) {
    io::read_safetensors(file);
  } else if (is("model_file")) {
    policy::Model::load(file);
  } else if (is("dataset_file")) {
    io::dataset_statistics(io::read_dataset_file(file));
  } else if (is("target_path")) {
    io::read_target_path(file);
  } else {
    FAIL() << name << ": name it <target>-<short>.bin, target one of scenario, target_path, projection_case, "
                      "safetensors, model_file, dataset_file";
  }
}

// Runs `body`, which must succeed or throw an io::InputError whose message starts with `source` and ": ".
template <typename Body>
void expect_read_or_refused(const std::string& source, Body&& body) {
  try {
    body();
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(source + ": ", 0), 0u) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an io::InputError: " << e.what();
  }
}

TEST(FuzzRegressions, EverySavedInputReadsOrIsRefusedWithAnInputError) {
  const std::vector<fs::path> files = saved_inputs();
  EXPECT_GE(files.size(), 2u) << "the saved inputs are missing from " << kRegressions;
  for (const fs::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    expect_read_or_refused(path.string(), [&] { read_as_target(path); });
  }
}

// The fuzzer's input: a number beyond double's range in the header. nlohmann throws out_of_range (not
// parse_error) for it, which escaped the reader.
TEST(FuzzRegressions, SafetensorsHeaderNumberOutOfRange) {
  const std::string path = (kRegressions / "safetensors-number-overflow.bin").string();
  try {
    io::read_safetensors(path);
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
}

// A dimension beyond int64 after a 0 (the byte count stays 0) was kept, stored negative, and the file that
// serialize_safetensors wrote from it did not read back.
TEST(FuzzRegressions, SafetensorsDimensionBeyondInt64) {
  const std::string path = (kRegressions / "safetensors-dimension-beyond-int64.bin").string();
  try {
    io::read_safetensors(path);
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shape is too large"), std::string::npos) << e.what();
  }
}

// A recorded path with a y of 1e308 (a finite number): the scenario maker rounded it to 4 decimals through
// 1e308 x 1e4, an infinity, and the simulator refused the scenario it had made with an exception the caller
// did not expect. Coordinates beyond 1e6 m are now refused first, as invalid samples.
TEST(FuzzRegressions, RecordedPathCoordinateNearTheLargestDouble) {
  const std::string path = (kRegressions / "target_path-coordinate-1e308.bin").string();
  const std::vector<core::TargetWaypoint> samples = io::read_target_path(path);
  ASSERT_EQ(samples.size(), 4u);
  EXPECT_EQ(samples[2].position.y(), 1e308);
  try {
    sim::scenario_from_recorded_path(core::Scenario{}, samples, {}, "fuzz");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample 2 lies more than 1000000 m from the origin"), std::string::npos)
        << e.what();
  }
}

// A NUL in a key (YAML '\0...', JSON "\u0000"): the message named the key as it was, and what() ended at the
// NUL, right after "FILE: ". Control characters in names from the file are now written \xNN.
TEST(FuzzRegressions, NulInAKeyIsWrittenOutInTheMessage) {
  const std::string scenario = (kRegressions / "scenario-nul-in-key.bin").string();
  try {
    io::read_scenario(scenario);
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(scenario + ": \\x00Mation8 naame7], yaw:", 0), 0u) << e.what();
  }
  const std::string projection_case = (kRegressions / "projection_case-nul-in-key.bin").string();
  try {
    io::read_projection_case(projection_case);
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(projection_case + ": \\x00: unknown key (expected one of: format,", 0), 0u)
        << e.what();
  }
  try {
    io::parse_projection_case(R"({"format": "occtrack.\u0007"})", "bell.json");
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "bell.json: format: expected \"occtrack.projection-case.v1\", got \"occtrack.\\x07\"");
  }
}

// A value nested 100000 levels deep where a string is expected: the message quoted it with json::dump(), which
// recurses per level and overflowed the stack. Built here (200 KB).
TEST(FuzzRegressions, ProjectionCaseDeeplyNestedValueInAMessage) {
  const int depth = 100000;
  const std::string text = "{\"format\": " + std::string(depth, '[') + std::string(depth, ']') + "}";
  try {
    io::parse_projection_case(text, "deep.json");
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()), "deep.json: format: must be a string, got a list nested more than 64 levels deep");
  }
}

// 10^5 samples whose first lists 10^5 obstacle points, each point empty: the reader sized the B x 4N matrix
// (320 GB) before it looked at a single point. Built here (1.2 MB).
TEST(FuzzRegressions, ProjectionCaseSizesNoMatrixBeforeReadingIt) {
  const int samples = 100000, points = 100000;
  std::string robot_velocity = "[", obstacles = "[[";
  for (int b = 0; b < samples; ++b) robot_velocity += b ? ",[0,0]" : "[0,0]";
  for (int j = 0; j < points; ++j) obstacles += j ? ",[]" : "[]";
  obstacles += "]";
  for (int b = 1; b < samples; ++b) obstacles += ",[]";
  const std::string text =
      R"({"format": "occtrack.projection-case.v1", "config": {"degree": 10, "steps": 100, "horizon": 5.0,
          "iterations": 10, "obstacle_radius": 0.4, "speed_min": 0.1, "speed_max": 2.0, "accel_max": 2.0,
          "via_steps": [49, 74], "rho": {"obstacle": 1, "velocity": 1, "acceleration": 1, "tracking": 1,
          "projection": 1}}, "inputs": {"robot_velocity": )" +
      robot_velocity + "], \"obstacles\": " + obstacles + "]}}";
  try {
    io::parse_projection_case(text, "wide.json");
    FAIL() << "expected an io::InputError";
  } catch (const io::InputError& e) {
    EXPECT_EQ(std::string(e.what()), "wide.json: inputs.obstacles[0][0]: expected 4 numbers, got 0");
  }
}

}  // namespace
}  // namespace occtrack
