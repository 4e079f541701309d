// Fuzz target: safetensors files (io::parse_safetensors, bytes in memory). A file that reads must convert
// every tensor, and serialize and read back to the same tensors and metadata.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "occtrack/io/safetensors.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::vector<unsigned char> bytes(data, data + size);
  fuzz::run(fuzz::Accept::input_error, "fuzz.safetensors", [&] {
    const io::TensorFile file = io::parse_safetensors(bytes, "fuzz.safetensors");
    for (const auto& [name, tensor] : file.tensors) {
      fuzz::check(tensor.numel() >= 0, "tensor '" + name + "' has a negative element count");
      fuzz::check(tensor.bytes.size() == static_cast<std::size_t>(tensor.numel()) * io::dtype_size(tensor.dtype),
                  "tensor '" + name + "' holds " + std::to_string(tensor.bytes.size()) + " bytes for shape " +
                      tensor.shape_text());
      fuzz::check(tensor.as_float().size() == static_cast<std::size_t>(tensor.numel()), "as_float size");
      fuzz::check(tensor.as_double().size() == static_cast<std::size_t>(tensor.numel()), "as_double size");
    }
    const std::vector<unsigned char> written = io::serialize_safetensors(file);
    io::TensorFile back;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "written.safetensors", [&] {
      back = io::parse_safetensors(written, "written.safetensors");
      read = true;
    });
    fuzz::check(read, "serialize_safetensors wrote a file that does not read back");
    fuzz::check(back.metadata == file.metadata, "metadata differs after a round trip");
    fuzz::check(back.tensors.size() == file.tensors.size(), "tensor count differs after a round trip");
    for (const auto& [name, tensor] : file.tensors) {
      const auto it = back.tensors.find(name);
      fuzz::check(it != back.tensors.end(), "tensor '" + name + "' lost in a round trip");
      fuzz::check(it->second.dtype == tensor.dtype && it->second.shape == tensor.shape &&
                      it->second.bytes == tensor.bytes,
                  "tensor '" + name + "' differs after a round trip");
    }
  });
  return 0;
}
