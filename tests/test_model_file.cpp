// The model file's contract (io/model_file.hpp) on its own: the tensor table against the shipped models and
// the random model, the writer and the reader as inverses, the metadata the writer adds, and policy::Model's
// refusal of a ModelFile changed after its check. (Refusals of broken files, through policy::Model, are in
// test_policy.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "occtrack/io/model_file.hpp"
#include "occtrack/policy/model.hpp"

using namespace occtrack;

namespace {

const std::string kModels = std::string(OCCTRACK_TEST_DATA_DIR) + "/../../models/";

std::set<std::string> names_of(const std::vector<io::TensorSpec>& specs) {
  std::set<std::string> names;
  for (const io::TensorSpec& s : specs) names.insert(s.name);
  return names;
}

std::set<std::string> names_of(const std::map<std::string, io::Tensor>& tensors) {
  std::set<std::string> names;
  for (const auto& [name, t] : tensors) names.insert(name);
  return names;
}

}  // namespace

TEST(ModelFile, ShippedModelsHoldExactlyTheTable) {
  for (const char* variant : {"cvae", "bc", "fixed-q"}) {
    SCOPED_TRACE(variant);
    const io::ModelFile m = io::read_model_file(kModels + variant + ".safetensors");
    EXPECT_EQ(io::to_string(m.variant), std::string(variant));
    io::NetworkConfig sizes = m.network;
    sizes.target_frame = false;  // what the networks see, not a size: the shipped cvae sees the target frame
    EXPECT_EQ(sizes, io::NetworkConfig{});  // the default sizes of docs/learning.md
    EXPECT_EQ(m.projection.iterations, 20);
    EXPECT_EQ(m.projection.obstacles, m.network.nearest_points);
    EXPECT_TRUE(m.projection_has_rho);
    ASSERT_TRUE(m.band.has_value());
    EXPECT_EQ(m.band->min, 1.0);
    EXPECT_EQ(m.band->max, 3.0);
    const std::vector<io::TensorSpec> table = io::model_tensors(m.network);
    EXPECT_EQ(table.size(), 88u);
    EXPECT_EQ(names_of(m.tensors), names_of(table));
    for (const io::TensorSpec& spec : table) EXPECT_EQ(m.tensors.at(spec.name).shape, spec.shape) << spec.name;
    EXPECT_EQ(m.values("decoder.out.bias").size(), 252u);
  }
}

TEST(ModelFile, TableNamesTheFieldEachDimensionFollows) {
  io::NetworkConfig c;
  c.hidden = 32;
  const std::vector<io::TensorSpec> table = io::model_tensors(c);
  const auto out = std::find_if(table.begin(), table.end(), [](const auto& s) { return s.name == "decoder.out.weight"; });
  ASSERT_NE(out, table.end());
  EXPECT_EQ(out->shape, (std::vector<std::int64_t>{252, 32}));
  EXPECT_EQ(out->fields, (std::vector<std::string>{"network.outputs", "network.hidden"}));
  EXPECT_EQ(table.front().name, "norm.observation.mean");
  EXPECT_EQ(table.back().name, "decoder.out.bias");
  int variances = 0;
  for (const io::TensorSpec& s : table) variances += s.role == io::TensorRole::norm_variance;
  EXPECT_EQ(variances, 5 + 1 + 2 * c.layers);  // PointNet's per-point and fc batch norms, encoder, decoder
}

TEST(ModelFile, WriterAndReaderAreInverses) {
  projection::Settings p;
  p.iterations = 30;
  const io::ModelFile m = io::validate_model_file(policy::random_model(io::NetworkConfig::for_projection(p), p, "fixed-q", 3));
  const io::TensorFile written = io::to_tensor_file(m);
  EXPECT_EQ(written.meta("format"), "occtrack.model.v1");
  EXPECT_EQ(written.meta("variant"), "fixed-q");
  EXPECT_EQ(nlohmann::json::parse(written.meta("projection")).at("training_iterations"), 30);
  EXPECT_EQ(written.meta("created_by"), "occtrack policy::random_model");
  const io::ModelFile back =
      io::validate_model_file(io::parse_safetensors(io::serialize_safetensors(written), "back.safetensors"));
  EXPECT_EQ(back.source, "back.safetensors");
  EXPECT_EQ(back.variant, io::Variant::fixed_q);
  EXPECT_EQ(back.network, m.network);
  EXPECT_EQ(back.projection, m.projection);
  EXPECT_EQ(back.metadata, written.metadata);
  ASSERT_EQ(back.tensors.size(), m.tensors.size());
  for (const auto& [name, t] : m.tensors) EXPECT_EQ(back.tensors.at(name).bytes, t.bytes) << name;
  // A file without a band reads without one, and is written without one.
  io::ModelFile no_band = m;
  no_band.band.reset();
  no_band.metadata.erase("band");
  EXPECT_FALSE(io::to_tensor_file(no_band).metadata.count("band"));
  EXPECT_FALSE(io::validate_model_file(io::to_tensor_file(no_band)).band.has_value());
  // Nor does the writer add a rho the file did not record (found by fuzz_model_file): the policy would then
  // refuse run settings whose rho differs from the default, which the file as read accepted.
  io::TensorFile no_rho_file = io::to_tensor_file(m);
  nlohmann::json projection = nlohmann::json::parse(no_rho_file.meta("projection"));
  ASSERT_TRUE(projection.contains("rho"));
  projection.erase("rho");
  no_rho_file.metadata["projection"] = projection.dump();
  const io::ModelFile no_rho = io::validate_model_file(no_rho_file);
  EXPECT_FALSE(no_rho.projection_has_rho);
  const io::TensorFile rewritten = io::to_tensor_file(no_rho);
  EXPECT_FALSE(nlohmann::json::parse(rewritten.meta("projection")).contains("rho"));
  EXPECT_FALSE(io::validate_model_file(rewritten).projection_has_rho);
  EXPECT_EQ(io::validate_model_file(rewritten).projection, no_rho.projection);
}

TEST(ModelFile, TheNetworkFrameIsRecordedAndOlderFilesAreRobotFrame) {
  const projection::Settings p;
  io::NetworkConfig config = io::NetworkConfig::for_projection(p);
  config.target_frame = true;
  io::TensorFile file = policy::random_model(config, p, "cvae", 6);
  EXPECT_EQ(nlohmann::json::parse(file.meta("network")).at("frame"), "target");
  EXPECT_TRUE(io::validate_model_file(file).network.target_frame);
  // Files written before issue 12 have no "frame": the robot frame, as they were trained.
  nlohmann::json network = nlohmann::json::parse(file.meta("network"));
  network.erase("frame");
  file.metadata["network"] = network.dump();
  EXPECT_FALSE(io::validate_model_file(file).network.target_frame);
  network["frame"] = "world";
  file.metadata["network"] = network.dump();
  file.source = "m.safetensors";
  try {
    io::validate_model_file(file);
    FAIL() << "accepted";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("network.frame"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, VariantSpellings) {
  for (const io::Variant v : {io::Variant::cvae, io::Variant::bc, io::Variant::fixed_q})
    EXPECT_EQ(io::parse_variant(io::to_string(v)), v);
  try {
    io::parse_variant("fixed_q");
    ADD_FAILURE() << "fixed_q accepted";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not one of cvae, bc, fixed-q"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, ThePolicyFoldsAFileOnlyAsChecked) {
  projection::Settings p;
  io::ModelFile m = io::validate_model_file(policy::random_model(io::NetworkConfig::for_projection(p), p, "cvae", 4));
  EXPECT_NO_THROW(policy::Model{m});
  // Changed after the check: the fold refuses it rather than reading past the tensor.
  io::TensorFile smaller;
  smaller.put("decoder.fc1.weight", {256, 128}, std::vector<float>(256 * 128, 0.0f));
  m.tensors["decoder.fc1.weight"] = smaller.tensors.at("decoder.fc1.weight");
  EXPECT_THROW(policy::Model{m}, std::invalid_argument);
  m.tensors.erase("decoder.fc1.weight");
  EXPECT_THROW(policy::Model{m}, io::InputError);
}

TEST(ModelFile, ValuesFromTheFileAreWrittenOutInMessages) {
  // A NUL in a metadata value would end the message at what() (the CLI prints only that far).
  const projection::Settings p;
  io::TensorFile file = policy::random_model(io::NetworkConfig::for_projection(p), p, "cvae", 5);
  file.source = "m.safetensors";
  file.metadata["variant"] = std::string("cv\0ae", 5);
  try {
    io::validate_model_file(file);
    FAIL() << "accepted";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("variant is 'cv\\x00ae'"), std::string::npos) << e.what();
  }
  file.metadata["variant"] = "cvae";
  file.metadata["format"] = std::string("occtrack\0model", 14);
  try {
    io::validate_model_file(file);
    FAIL() << "accepted";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("format is 'occtrack\\x00model'"), std::string::npos) << e.what();
  }
}

TEST(ModelFile, SizesBeyondTheBoundsAreRefusedBeforeAnyWorkspace) {
  io::NetworkConfig c;
  c.cloud_points = 1000000000;  // once reserved 8 GB of PointNet workspace (fuzz_model_file)
  std::string error;
  EXPECT_FALSE(c.validate(&error));
  EXPECT_EQ(error, "cloud_points (1000000000) must be at most 100000");
  c = {};
  c.pointnet_widths.assign(65, 8);
  EXPECT_FALSE(c.validate(&error));
  EXPECT_NE(error.find("pointnet_widths holds 65 widths"), std::string::npos) << error;
}
