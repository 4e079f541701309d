// The trainer reads dataset files through the one reader (io::read_dataset_file): the file the first generator
// wrote and its float64/int64 twin load into the same tensors, equal to io's values; files without the
// optional metadata load too.
#include <gtest/gtest.h>

#include <dirent.h>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

#include "learning/dataset.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/safetensors.hpp"

namespace fs = std::filesystem;
using namespace occtrack;

namespace {

// See tests/test_dataset_file.cpp: written by `occtrack dataset generate` at commit 67d4173.
const std::string kV1Sim = std::string(OCCTRACK_TEST_DATA_DIR) + "/datasets/v1-sim.safetensors";

template <typename T>
std::vector<T> values_of(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous();
  return std::vector<T>(c.data_ptr<T>(), c.data_ptr<T>() + c.numel());
}

// A file in the test's own temporary folder (removed with POSIX calls: LibTorch wheels may interpose
// std::filesystem, see test_training.cpp).
struct TempFile {
  std::string path;
  explicit TempFile(const std::string& name)
      : path((fs::temp_directory_path() / ("occtrack_dataset_files_" + std::to_string(::getpid()) + "_" + name))
                 .string()) {}
  ~TempFile() { ::unlink(path.c_str()); }
};

void expect_tensors_hold(const learning::Dataset& d, const io::DatasetFile& f) {
  ASSERT_EQ(d.rows(), f.rows);
  EXPECT_EQ(d.cloud_points(), f.cloud_points);
  EXPECT_EQ(d.nearest_points(), f.nearest_points);
  EXPECT_EQ(d.coefficients(), f.coefficients);
  EXPECT_EQ(d.observation.scalar_type(), torch::kFloat32);
  EXPECT_EQ(d.episode.scalar_type(), torch::kInt64);
  EXPECT_EQ(values_of<float>(d.observation), f.observation);
  EXPECT_EQ(values_of<float>(d.cloud), f.cloud);
  EXPECT_EQ(values_of<float>(d.obstacles), f.obstacles);
  EXPECT_EQ(values_of<float>(d.expert_xi), f.expert_xi);
  EXPECT_EQ(values_of<float>(d.expert_cost), f.expert_cost);
  EXPECT_EQ(values_of<float>(d.time), f.time);
  const std::vector<int64_t> episode = values_of<int64_t>(d.episode);
  EXPECT_EQ(std::vector<std::int32_t>(episode.begin(), episode.end()), f.episode);
}

}  // namespace

TEST(DatasetFiles, TheFirstGeneratorsFileLoadsAsIoReadsIt) {
  const io::DatasetFile f = io::read_dataset_file(kV1Sim);
  const learning::Dataset d = learning::load_dataset({kV1Sim});
  expect_tensors_hold(d, f);
  EXPECT_EQ(d.projection, io::dataset_projection(f));
  ASSERT_EQ(d.files.size(), 1u);
  EXPECT_EQ(d.files[0].path, kV1Sim);
  EXPECT_EQ(d.files[0].rows, 20);
  EXPECT_EQ(d.files[0].episodes, 1);
}

TEST(DatasetFiles, Float64AndInt64ColumnsLoadToTheSameTensors) {
  const io::TensorFile raw = io::read_safetensors(kV1Sim);
  io::TensorFile wide = raw;
  for (const auto& [name, t] : raw.tensors) {
    if (name == "episode") {
      const std::vector<double> e = t.as_double();
      wide.put(name, t.shape, std::vector<std::int64_t>(e.begin(), e.end()));
    } else {
      wide.put(name, t.shape, t.as_double());
    }
  }
  // As the trainer's own tests wrote files: without `perception`.
  wide.metadata.erase("perception");
  const TempFile file("wide.safetensors");
  io::write_safetensors(file.path, wide);
  ASSERT_EQ(io::read_safetensors(file.path).at("expert_xi").dtype, io::DType::F64);

  const learning::Dataset narrow = learning::load_dataset({kV1Sim});
  const learning::Dataset d = learning::load_dataset({file.path});
  expect_tensors_hold(d, io::read_dataset_file(kV1Sim));
  EXPECT_TRUE(torch::equal(d.cloud, narrow.cloud));

  // Both together: rows add up, episodes stay apart.
  const learning::Dataset both = learning::load_dataset({kV1Sim, file.path});
  EXPECT_EQ(both.rows(), 40);
  EXPECT_EQ(std::get<0>(torch::_unique(both.episode)).numel(), 2);
}

TEST(DatasetFiles, AFileWithNoRowsIsRefusedForTraining) {
  io::DatasetFile empty = io::read_dataset_file(kV1Sim);
  empty.rows = 0;
  for (auto* v : {&empty.observation, &empty.cloud, &empty.obstacles, &empty.expert_xi, &empty.expert_cost, &empty.time})
    v->clear();
  empty.episode.clear();
  const io::DatasetFile back = io::validate_dataset_file(io::to_tensor_file(empty));  // a valid file
  EXPECT_EQ(back.rows, 0);
  try {
    learning::make_dataset({back});
    ADD_FAILURE() << "an empty dataset was accepted for training";
  } catch (const io::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the dataset has no rows"), std::string::npos) << e.what();
  }
}
