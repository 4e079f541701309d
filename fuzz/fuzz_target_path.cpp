// Fuzz target: recorded target paths (io::parse_target_path, a text table). What reads must hold finite,
// strictly increasing samples; then sim::scenario_from_recorded_path makes a scenario of it (stretches up to
// 600 s) in a world of one circle and one moving box, resampled in the world's frame and kept as recorded in a
// frame the input's second byte picks, which must read back as a scenario file.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/io/target_path.hpp"
#include "occtrack/sim/recorded_path.hpp"

namespace {

occtrack::core::Scenario small_world() {
  using occtrack::core::ObstacleSpec;
  occtrack::core::Scenario world;
  ObstacleSpec circle;
  circle.center = {5.0, 0.0};
  circle.radius = 1.0;
  ObstacleSpec box;
  box.shape = ObstacleSpec::Shape::box;
  box.center = {-5.0, 5.0};
  box.size = {1.6, 0.7};
  box.path = {{-5.0, 5.0}, {-5.0, 8.0}};
  box.speed = 0.7;
  world.obstacles = {circle, box};
  return world;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::string text(reinterpret_cast<const char*>(data), size);
  // The default columns, then named ones (the first byte picks the time scale, so that large clocks occur).
  const io::TargetPathColumns named{"t", "x", "y", size > 0 && data[0] % 2 ? 1e-9 : 1.0};
  for (const io::TargetPathColumns& columns : {io::TargetPathColumns{}, named}) {
    std::vector<core::TargetWaypoint> samples;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "fuzz.csv", [&] {
      samples = io::parse_target_path(text, "fuzz.csv", columns);
      read = true;
    });
    if (!read) continue;
    fuzz::check(samples.size() >= 2, "fewer than two samples read");
    for (std::size_t k = 0; k < samples.size(); ++k) {
      fuzz::check(std::isfinite(samples[k].time) && samples[k].position.allFinite(), "a sample is not finite");
      fuzz::check(k == 0 || samples[k].time > samples[k - 1].time, "times do not strictly increase");
    }
    // Long stretches only take longer (up to a million waypoints; the cap is tested in
    // tests/test_recorded_path.cpp): keep each input fast.
    if (samples.back().time - samples.front().time > 600.0) continue;
    for (const double period : {0.1, 0.0}) {
      sim::RecordedPathSettings settings;
      settings.period = period;
      if (period == 0.0 && size > 1) {  // a frame from the second byte: turns up to a full turn, offsets to 1e6 m
        settings.rotation = (data[1] % 64 - 32) * (2.0 * std::numbers::pi / 32.0);
        settings.offset = core::Vec2(data[1] % 3 == 0 ? 1e6 : 3.5, data[1] % 5 == 0 ? -1e6 : -2.0);
      }
      core::Scenario scenario;
      bool made = false;
      try {
        scenario = sim::scenario_from_recorded_path(small_world(), samples, settings, "fuzz");
        made = true;
      } catch (const std::runtime_error& e) {  // documented: a stretch too short or too long, no robot start
        fuzz::check(std::string(e.what()).rfind("recorded path: ", 0) == 0,
                    std::string("an unexplained runtime_error: ") + e.what());
      } catch (const std::invalid_argument& e) {  // documented: samples out of bounds
        fuzz::check(std::string(e.what()).rfind("recorded path: ", 0) == 0,
                    std::string("an unexplained invalid_argument: ") + e.what());
      }
      if (!made) continue;
      const std::string written = io::scenario_yaml(scenario);
      bool read_back = false;
      fuzz::run(fuzz::Accept::input_error, "made.yaml", [&] {
        io::parse_scenario(written, "made.yaml");
        read_back = true;
      });
      fuzz::check(read_back, "a made scenario does not read back:\n" + written.substr(0, 2000));
    }
  }
  return 0;
}
