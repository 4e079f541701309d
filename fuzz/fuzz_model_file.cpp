// Fuzz target: model files (safetensors bytes -> io::validate_model_file, the contract of docs/learning.md's
// "Model file"). A file that passes must write and check again to the same contents, fold into a
// policy::Model that agrees with its own projection settings, and run one planning cycle's inference
// (features, decode, postprocess) on a small cloud and batch.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_common.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/policy/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occtrack;
  const std::vector<unsigned char> bytes(data, data + size);
  const std::string source = "fuzz-model.safetensors";
  fuzz::run(fuzz::Accept::input_error, source, [&] {
    const io::ModelFile file = io::validate_model_file(io::parse_safetensors(bytes, source));

    const std::vector<unsigned char> written = io::serialize_safetensors(io::to_tensor_file(file));
    io::ModelFile back;
    bool read = false;
    fuzz::run(fuzz::Accept::input_error, "written.safetensors", [&] {
      back = io::validate_model_file(io::parse_safetensors(written, "written.safetensors"));
      read = true;
    });
    fuzz::check(read, "a model file that passed does not pass again after to_tensor_file");
    fuzz::check(back.variant == file.variant && back.network == file.network && back.projection == file.projection &&
                    back.projection_has_rho == file.projection_has_rho &&
                    back.band.has_value() == file.band.has_value() && back.tensors.size() == file.tensors.size(),
                "model file differs after a round trip");
    for (const auto& [name, tensor] : file.tensors) {
      const auto it = back.tensors.find(name);
      fuzz::check(it != back.tensors.end() && it->second.dtype == tensor.dtype && it->second.shape == tensor.shape &&
                      it->second.bytes == tensor.bytes,
                  "tensor '" + name + "' differs after a round trip");
    }

    // Folding and inference: the contract says a checked file is usable.
    fuzz::run(fuzz::Accept::documented, source, [&] {
      policy::Model model(file);
      model.check_projection(model.projection());
      const io::NetworkConfig& network = model.network();
      policy::Cloud cloud(3, 2);
      cloud << 1.0f, 0.5f, -2.0f, 1.0f, 0.0f, -3.0f;
      Eigen::VectorXf features(network.features);
      model.features(cloud, features);
      const Eigen::VectorXf observation = Eigen::VectorXf::Constant(network.observation, 0.5f);
      const policy::Rows z = policy::Rows::Constant(2, network.latent, 0.25f);
      policy::Rows outputs(2, network.outputs);
      model.decode(z, observation, features, outputs);
      model.postprocess(outputs, model.projection().speed_max, 1.0);
    });
  });
  return 0;
}
