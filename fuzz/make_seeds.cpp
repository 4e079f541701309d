// Writes the generated part of the seed corpus (fuzz/corpus/): tiny model, dataset, safetensors and projection
// case files, each a few kilobytes, so that the fuzzers start from valid files without shipping the 2 MB models.
// The scenario seeds are copies of tests/data/scenarios and scenarios/*-smoke files.
//
//   build-fuzz/fuzz/fuzz_make_seeds fuzz/corpus
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/policy/model.hpp"
#include "occtrack/sim/demonstrations.hpp"

namespace {

using namespace occtrack;
namespace fs = std::filesystem;

// The smallest sizes projection::Settings::validate accepts, near them.
projection::Settings tiny_projection() {
  projection::Settings s;
  s.degree = 5;
  s.steps = 10;
  s.via_step_1 = 4;
  s.via_step_2 = 7;
  s.obstacles = 2;
  s.batch = 2;
  s.iterations = 3;
  return s;
}

io::NetworkConfig tiny_network(const projection::Settings& projection) {
  io::NetworkConfig c = io::NetworkConfig::for_projection(projection);
  c.cloud_points = 4;
  c.latent = 2;
  c.pointnet_widths = {3, 4};
  c.pointnet_hidden = 4;
  c.features = 3;
  c.hidden = 4;
  c.layers = 2;
  return c;
}

void write_bytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
  std::cout << path.string() << " (" << bytes.size() << " bytes)\n";
}

void write_text(const fs::path& path, const std::string& text) {
  write_bytes(path, std::vector<unsigned char>(text.begin(), text.end()));
}

io::DatasetFile tiny_dataset(std::int64_t rows) {
  sim::DemonstrationSettings settings;
  settings.expert.projection = tiny_projection();
  settings.expert.perception.cloud_size = 3;
  settings.expert.perception.nearest_count = 2;
  settings.episodes = 1;
  io::DatasetFile d;
  d.metadata = sim::demonstration_metadata(settings);
  d.rows = rows;
  d.cloud_points = 3;
  d.nearest_points = 2;
  d.coefficients = settings.expert.projection.coefficients();
  auto values = [](std::int64_t count, float start) {
    std::vector<float> v(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = start + 0.25f * static_cast<float>(i % 7);
    return v;
  };
  d.observation = values(rows * io::kObservationSize, -1.0f);
  d.cloud = values(rows * d.cloud_points * 2, 0.5f);
  d.obstacles = values(rows * d.nearest_points * 4, -0.5f);
  d.expert_xi = values(rows * 2 * d.coefficients, 0.0f);
  d.expert_cost = values(rows, 2.0f);
  for (std::int64_t r = 0; r < rows; ++r) {
    d.episode.push_back(static_cast<std::int32_t>(r / 2));
    d.time.push_back(0.1f * static_cast<float>(r));
  }
  return d;
}

io::ProjectionCase tiny_case(int obstacles) {
  io::ProjectionCase c;
  c.name = "tiny";
  c.description = "fuzz seed";
  c.settings = tiny_projection();
  c.settings.batch = 1;
  c.settings.obstacles = obstacles;
  const int n = c.settings.coefficients(), m = c.settings.steps;
  auto& p = c.problem;
  p.robot_velocity = projection::RowMatrix<double>::Constant(1, 2, 0.5);
  p.obstacles = projection::RowMatrix<double>::Constant(1, 4 * obstacles, 1.5);
  p.target = projection::RowMatrix<double>::Constant(1, 4, 2.0);
  p.terminal = projection::RowMatrix<double>::Constant(1, 4, 3.0);
  p.via_points = projection::RowMatrix<double>::Constant(1, 4, 1.0);
  p.lambda0 = projection::RowMatrix<double>::Zero(1, 2 * n);
  p.distance_min = projection::RowMatrix<double>::Constant(1, m, 1.0);
  p.distance_max = projection::RowMatrix<double>::Constant(1, m, 3.0);
  p.xi_bar = projection::RowMatrix<double>::Constant(1, 2 * n, 0.25);
  return c;
}

// The same file with every F32 tensor as F64 and every I32 as I64 (the readers accept both).
io::TensorFile widened(const io::TensorFile& file) {
  io::TensorFile out;
  out.metadata = file.metadata;
  for (const auto& [name, t] : file.tensors) {
    if (t.dtype == io::DType::F32) {
      out.put(name, t.shape, t.as_double());
    } else if (t.dtype == io::DType::I32) {
      std::vector<std::int64_t> values;
      for (double v : t.as_double()) values.push_back(static_cast<std::int64_t>(v));
      out.put(name, t.shape, values);
    } else {
      out.tensors[name] = t;
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_make_seeds CORPUS_DIR\n";
    return 2;
  }
  const fs::path root = argv[1];
  for (const char* name : {"model_file", "dataset_file", "safetensors", "projection_case"})
    fs::create_directories(root / name);

  const projection::Settings projection = tiny_projection();
  const io::NetworkConfig network = tiny_network(projection);
  std::uint64_t seed = 1;
  for (const char* variant : {"cvae", "bc", "fixed-q"}) {
    const io::TensorFile model = policy::random_model(network, projection, variant, seed++);
    policy::Model check(model);  // the seed must pass the contract
    write_bytes(root / "model_file" / (std::string("tiny-") + variant + ".safetensors"),
                io::serialize_safetensors(model));
  }
  {
    io::TensorFile model = widened(policy::random_model(network, projection, "cvae", seed++));
    model.metadata.erase("band");  // optional
    policy::Model check(model);
    write_bytes(root / "model_file" / "tiny-cvae-f64-no-band.safetensors", io::serialize_safetensors(model));
  }

  for (std::int64_t rows : {0, 1, 3}) {
    const io::TensorFile dataset = io::to_tensor_file(tiny_dataset(rows));
    io::validate_dataset_file(dataset);  // the seed must pass the contract
    write_bytes(root / "dataset_file" / ("tiny-" + std::to_string(rows) + "-rows.safetensors"),
                io::serialize_safetensors(dataset));
  }
  {
    io::TensorFile dataset = widened(io::to_tensor_file(tiny_dataset(2)));
    dataset.metadata.erase("perception");  // optional: sizes from the tensors
    dataset.metadata.erase("rows");
    io::validate_dataset_file(dataset);
    write_bytes(root / "dataset_file" / "tiny-2-rows-f64-i64.safetensors", io::serialize_safetensors(dataset));
  }

  io::TensorFile plain;
  plain.metadata["note"] = "fuzz seed";
  plain.put("f32", {2, 3}, std::vector<float>{1, 2, 3, 4, 5, 6});
  plain.put("f64", {3}, std::vector<double>{-1.5, 0.0, 1e300});
  plain.put("i32", {1, 2}, std::vector<std::int32_t>{-7, 7});
  plain.put("i64", {2}, std::vector<std::int64_t>{-(std::int64_t{1} << 40), 3});
  plain.put("empty", {0, 4}, std::vector<float>{});
  plain.put("scalar", {}, std::vector<float>{42.0f});
  write_bytes(root / "safetensors" / "four-dtypes.safetensors", io::serialize_safetensors(plain));
  io::TensorFile empty;
  write_bytes(root / "safetensors" / "no-tensors.safetensors", io::serialize_safetensors(empty));

  write_text(root / "projection_case" / "tiny-no-obstacles.json", io::projection_case_json(tiny_case(0)));
  write_text(root / "projection_case" / "tiny-two-obstacles.json", io::projection_case_json(tiny_case(2), 1));
  return 0;
}
