// Fuzz target: projection case files (io::parse_projection_case, JSON). A case that reads must also write and
// read back to the same case.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "occtrack/io/projection_case.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::run(fuzz::Accept::input_error, "fuzz.json", [&] {
    const io::ProjectionCase c = io::parse_projection_case(text, "fuzz.json");
    const std::string written = io::projection_case_json(c);
    io::ProjectionCase back;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "written.json", [&] {
      back = io::parse_projection_case(written, "written.json");
      read = true;
    });
    fuzz::check(read, "projection_case_json wrote a case that does not read back:\n" + written);
    fuzz::check(io::projection_case_json(back) == written, "projection_case_json does not round-trip:\n" + written);
  });
  return 0;
}
