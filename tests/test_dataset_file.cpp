// The dataset file's contract (io/dataset_file.hpp): a file written by the first generator (before the
// contract moved to io) still reads and rewrites to the same bytes; float64 and int64 columns read as their
// float32 and int32 values; optional metadata is checked when present; broken files are refused naming the
// file and the key or tensor.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/safetensors.hpp"

using namespace occtrack;

namespace {

// `occtrack dataset generate --episodes 1 --duration 1 --expert-samples 64 --expert-iterations 1 --jobs 1`,
// run with the code of commit 67d4173 (sim/demonstrations.cpp wrote the file then).
const std::string kV1Sim = std::string(OCCTRACK_TEST_DATA_DIR) + "/datasets/v1-sim.safetensors";

std::vector<unsigned char> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The same file with float64 columns and an int64 episode column, as other writers have produced.
io::TensorFile widened(const io::TensorFile& file) {
  io::TensorFile wide = file;
  for (const auto& [name, t] : file.tensors) {
    if (name == "episode") {
      const std::vector<double> e = t.as_double();
      wide.put(name, t.shape, std::vector<std::int64_t>(e.begin(), e.end()));
    } else {
      wide.put(name, t.shape, t.as_double());
    }
  }
  return wide;
}

// The message of the io::InputError that reading `file` throws ("" when it throws none).
std::string refusal(const io::TensorFile& file) {
  try {
    io::validate_dataset_file(file);
  } catch (const io::InputError& e) {
    return e.what();
  }
  return "";
}

void expect_same_rows(const io::DatasetFile& a, const io::DatasetFile& b) {
  EXPECT_EQ(a.rows, b.rows);
  EXPECT_EQ(a.cloud_points, b.cloud_points);
  EXPECT_EQ(a.nearest_points, b.nearest_points);
  EXPECT_EQ(a.coefficients, b.coefficients);
  EXPECT_EQ(a.observation, b.observation);
  EXPECT_EQ(a.cloud, b.cloud);
  EXPECT_EQ(a.obstacles, b.obstacles);
  EXPECT_EQ(a.expert_xi, b.expert_xi);
  EXPECT_EQ(a.expert_cost, b.expert_cost);
  EXPECT_EQ(a.episode, b.episode);
  EXPECT_EQ(a.time, b.time);
}

}  // namespace

TEST(DatasetFile, ReadsTheFirstGeneratorsFileAndRewritesItsBytes) {
  const io::TensorFile raw = io::read_safetensors(kV1Sim);
  const io::DatasetFile d = io::read_dataset_file(kV1Sim);
  EXPECT_EQ(d.source, kV1Sim);
  EXPECT_EQ(d.rows, 20);
  EXPECT_EQ(d.cloud_points, 200);
  EXPECT_EQ(d.nearest_points, 60);
  EXPECT_EQ(d.coefficients, 11);
  EXPECT_EQ(d.metadata, raw.metadata);
  EXPECT_EQ(d.observation, raw.at("observation").as_float());
  EXPECT_EQ(d.cloud, raw.at("cloud").as_float());
  EXPECT_EQ(d.expert_xi, raw.at("expert_xi").as_float());
  EXPECT_EQ(d.episode, std::vector<std::int32_t>(20, 0));
  EXPECT_EQ(d.time.front(), 0.0f);
  EXPECT_EQ(io::dataset_projection(d).degree, 10);
  // The writer is the one that wrote it: same metadata, tensors and layout, byte for byte.
  EXPECT_TRUE(io::serialize_safetensors(io::to_tensor_file(d)) == file_bytes(kV1Sim));

  const io::DatasetStatistics s = io::dataset_statistics(d);
  EXPECT_EQ(s.rows, 20);
  EXPECT_EQ(s.episodes, 1);
  EXPECT_GT(s.plan_speed_mean, 0.0);
  EXPECT_TRUE(std::isfinite(s.cost_mean));
  EXPECT_NEAR(s.target_distance_mean, 2.0, 0.6);  // the generator starts the target about 2 m away
}

TEST(DatasetFile, ReadsFloat64AndInt64ColumnsAsTheirFloat32Values) {
  const io::TensorFile raw = io::read_safetensors(kV1Sim);
  const io::TensorFile wide = widened(raw);
  ASSERT_EQ(wide.at("cloud").dtype, io::DType::F64);
  ASSERT_EQ(wide.at("episode").dtype, io::DType::I64);
  const io::DatasetFile back = io::validate_dataset_file(io::parse_safetensors(io::serialize_safetensors(wide), "wide"));
  EXPECT_EQ(back.source, "wide");
  expect_same_rows(back, io::validate_dataset_file(raw));
  // Written back, it is float32 and int32 again.
  EXPECT_EQ(io::to_tensor_file(back).at("episode").dtype, io::DType::I32);
  EXPECT_EQ(io::to_tensor_file(back).at("cloud").dtype, io::DType::F32);
}

TEST(DatasetFile, RowsAndPerceptionAreOptionalButCheckedWhenPresent) {
  const io::TensorFile raw = io::read_safetensors(kV1Sim);
  io::TensorFile bare = raw;
  bare.metadata.erase("rows");
  bare.metadata.erase("perception");
  expect_same_rows(io::validate_dataset_file(bare), io::validate_dataset_file(raw));

  io::TensorFile f = raw;
  f.metadata["rows"] = "21";
  std::string m = refusal(f);
  EXPECT_NE(m.find("tensor 'observation' has shape [20, 6], expected [21, 6]"), std::string::npos) << m;
  f.metadata["rows"] = "twenty";
  m = refusal(f);
  EXPECT_NE(m.find("metadata 'rows' ('twenty') is not a row count"), std::string::npos) << m;

  f = raw;
  nlohmann::json perception = nlohmann::json::parse(f.meta("perception"));
  perception["cloud_size"] = 100;
  f.metadata["perception"] = perception.dump();
  m = refusal(f);
  EXPECT_NE(m.find(kV1Sim), std::string::npos) << m;
  EXPECT_NE(m.find("tensor 'cloud' has shape [20, 200, 2], expected [20, 100, 2]"), std::string::npos) << m;
  perception.erase("nearest_count");
  f.metadata["perception"] = perception.dump();
  EXPECT_NE(refusal(f).find("'nearest_count' must be an integer"), std::string::npos);
}

TEST(DatasetFile, RefusesBrokenFilesNamingTheKeyOrTensor) {
  const io::TensorFile raw = io::read_safetensors(kV1Sim);
  auto expect_refused = [&](const io::TensorFile& f, const std::string& what) {
    const std::string m = refusal(f);
    EXPECT_NE(m.find(kV1Sim + ": "), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << "'" << what << "' in: " << m;
  };
  io::TensorFile f = raw;
  f.metadata["format"] = "occtrack.model.v1";
  expect_refused(f, "metadata 'format' is 'occtrack.model.v1', expected 'occtrack.dataset.v1'");
  f = raw;
  f.metadata.erase("projection");
  expect_refused(f, "metadata 'projection' is missing");
  f = raw;
  f.metadata["projection"] = R"({"degree": 10})";
  expect_refused(f, "projection.steps");
  f = raw;
  f.put("episode", {20}, std::vector<float>(20, 0.0f));
  expect_refused(f, "tensor 'episode' has dtype F32, expected I32 or I64");
  f = raw;
  f.put("time", {20}, std::vector<std::int32_t>(20, 0));
  expect_refused(f, "tensor 'time' has dtype I32, expected F32 or F64");
  f = raw;
  std::vector<std::int64_t> episode(20, 0);
  episode[7] = -1;
  f.put("episode", {20}, episode);
  expect_refused(f, "tensor 'episode' has a negative index in row 7");
  episode[7] = std::int64_t{1} << 40;
  f.put("episode", {20}, episode);
  expect_refused(f, "tensor 'episode' holds an index beyond int32 in row 7");
  f = raw;
  std::vector<double> cost = f.at("expert_cost").as_double();
  cost[4] = std::numeric_limits<double>::infinity();
  f.put("expert_cost", {20}, cost);
  expect_refused(f, "tensor 'expert_cost' holds a non-finite value in row 4");
  f = raw;
  f.metadata.erase("perception");
  f.put("cloud", {20, 0, 2}, std::vector<float>{});
  expect_refused(f, "tensor 'cloud' has no points");
  f = raw;
  f.metadata.erase("rows");
  f.tensors.erase("observation");
  expect_refused(f, "tensor 'observation' is missing");
}

TEST(DatasetFile, AppendRenumbersEpisodesAndRefusesOtherSettings) {
  const io::DatasetFile d = io::read_dataset_file(kV1Sim);
  io::DatasetFile merged;
  io::append_dataset(merged, d);
  io::append_dataset(merged, d);
  EXPECT_EQ(merged.rows, 40);
  EXPECT_EQ(std::set<std::int32_t>(merged.episode.begin(), merged.episode.end()), (std::set<std::int32_t>{0, 1}));
  EXPECT_EQ(merged.metadata.at("rows"), "40");
  EXPECT_EQ(io::dataset_statistics(merged).episodes, 2);
  const io::DatasetFile back = io::validate_dataset_file(io::to_tensor_file(merged));
  expect_same_rows(back, merged);

  io::DatasetFile other = d;
  other.metadata["perception"] = "{}";
  EXPECT_THROW(io::append_dataset(merged, other), std::invalid_argument);
  other = d;
  other.cloud_points = 100;
  EXPECT_THROW(io::append_dataset(merged, other), std::invalid_argument);
  // A vector that does not match the sizes is refused by the writer.
  other = d;
  other.time.pop_back();
  EXPECT_THROW(io::to_tensor_file(other), std::invalid_argument);
}
