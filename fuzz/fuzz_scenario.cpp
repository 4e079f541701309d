// Fuzz target: scenario files (io::parse_scenario, YAML). A scenario that reads must also write and read back
// to the same scenario (io::scenario_yaml promises an exact round trip).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "occtrack/io/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::run(fuzz::Accept::input_error, "fuzz.yaml", [&] {
    const core::Scenario scenario = io::parse_scenario(text, "fuzz.yaml");
    const std::string written = io::scenario_yaml(scenario);
    core::Scenario back;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "written.yaml", [&] {
      back = io::parse_scenario(written, "written.yaml");
      read = true;
    });
    fuzz::check(read, "scenario_yaml wrote a scenario that does not read back:\n" + written);
    fuzz::check(io::scenario_yaml(back) == written, "scenario_yaml does not round-trip:\n" + written);
  });
  return 0;
}
