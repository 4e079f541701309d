// Fuzz target: dataset files (safetensors bytes -> io::validate_dataset_file, docs/learning.md's "Dataset
// file"). A file that passes must give its statistics (as `occtrack dataset info` does) or refuse them with
// an io::InputError, and write and check again to the same rows.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_common.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/safetensors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::vector<unsigned char> bytes(data, data + size);
  const std::string source = "fuzz-dataset.safetensors";
  fuzz::run(fuzz::Accept::input_error, source, [&] {
    const io::DatasetFile d = io::validate_dataset_file(io::parse_safetensors(bytes, source));
    fuzz::run(fuzz::Accept::documented, source, [&] { io::dataset_statistics(d); });

    const std::vector<unsigned char> written = io::serialize_safetensors(io::to_tensor_file(d));
    io::DatasetFile back;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "written.safetensors", [&] {
      back = io::validate_dataset_file(io::parse_safetensors(written, "written.safetensors"));
      read = true;
    });
    fuzz::check(read, "a dataset file that passed does not pass again after to_tensor_file");
    fuzz::check(back.rows == d.rows && back.cloud_points == d.cloud_points && back.nearest_points == d.nearest_points &&
                    back.coefficients == d.coefficients && back.observation == d.observation &&
                    back.cloud == d.cloud && back.obstacles == d.obstacles && back.expert_xi == d.expert_xi &&
                    back.episode == d.episode && back.time == d.time && back.expert_cost == d.expert_cost,
                "dataset differs after a round trip");
  });
  return 0;
}
