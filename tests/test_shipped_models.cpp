// The shipped models (models/*.safetensors) through the run-time policy: PointNet features and decoder
// outputs on a fixed cloud, observation and latent batch, against values recorded with the code that shipped
// them (policy/model.cpp before the model-file contract moved to io/model_file). Folding and inference must
// not change what a shipped model computes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "occtrack/policy/model.hpp"

using namespace occtrack;

namespace {

const std::string kModels = std::string(OCCTRACK_TEST_DATA_DIR) + "/../../models/";

// A deterministic cloud of C points on two interleaved spirals, robot-centric metres.
policy::Cloud fixed_cloud(int points) {
  policy::Cloud cloud(points, 2);
  for (int i = 0; i < points; ++i) {
    const double r = 1.5 + 0.02 * i, a = 0.11 * i;
    cloud(i, 0) = static_cast<float>(r * std::cos(3.7 * a));
    cloud(i, 1) = static_cast<float>(r * std::sin(2.3 * a));
  }
  return cloud;
}

// Columns of the decoder outputs that are compared: some of every block of the default layout (Y = 252).
const int kColumns[] = {0, 3, 5, 8, 29, 30, 80, 131, 150, 230, 241, 251};
const int kRows[] = {0, 2, 4};

struct Golden {
  std::string name;
  std::vector<double> features;  // at 0, 8, ..., 56 and F - 1
  std::vector<double> outputs;   // rows kRows x columns kColumns
};

// The values the model computes now.
Golden compute(policy::Model& model) {
  const int F = model.network().features, Y = model.network().outputs, Z = model.network().latent;
  Eigen::VectorXf features(F);
  model.features(fixed_cloud(model.network().cloud_points), features);
  Eigen::VectorXf observation(6);
  observation << 0.4f, -0.3f, 2.6f, 1.1f, 0.5f, -0.2f;
  policy::Rows z(5, Z);
  for (int b = 0; b < 5; ++b)
    for (int k = 0; k < Z; ++k) z(b, k) = static_cast<float>(-1.0 + 0.5 * b + 0.3 * k);
  policy::Rows out(5, Y);
  model.decode(z, observation, features, out);
  Golden g{model.source(), {}, {}};
  for (int i = 0; i < F; i += 8) g.features.push_back(features(i));
  g.features.push_back(features(F - 1));
  for (int b : kRows)
    for (int j : kColumns) g.outputs.push_back(out(b, j));
  return g;
}

// Recorded with policy/model.cpp at 2e97193 (float32 inference, -march=native, printed with %.9g); the cvae
// again when its model was replaced.
const Golden kGolden[] = {
    {"cvae",  // the DAgger model shipped on 2026-12-01 (target frame), recorded then the same way
     {0.138563961, -0.111075193, -0.00734755443, 0.0326534994, -0.0488756187, -0.111048594, 0.283747792, -0.103860572, -0.222432509},
     {-168.504898, -2.66895723, -77.1867981, 6.30964613, -5.88596773, -94.3580627, -65.9406204, 833.453125, 592.569885, -0.00409817649, 0.0153049249, -10.2498636, -169.176697, -2.64901257, -76.8005905, 6.31129932, -5.87616444, -94.296669, -65.8981018, 832.981689, 592.179138, -0.00410254439, 0.0153069757, -10.1861849, -169.848465, -2.62907195, -76.4142914, 6.31295443, -5.86635637, -94.2353592, -65.8555603, 832.510315, 591.788574, -0.00410692068, 0.0153090237, -10.12251}},
    {"bc",
     {0.493151367, -1.01064777, -0.0818229094, 0.0206977427, 0.976515889, -0.264625758, 0.392502457, 0.233951166, -0.296110362},
     {-0.00677859038, -0.010660789, -0.116024502, 0.0325750671, -0.0293047335, 1.01586342, 1.0068742, 2.99327898, 3.0226655, -0.00710384129, -0.00289478456, 0.829777181, -0.0381737873, 0.00125879422, -0.13109003, 0.0263024569, -0.0138275474, 1.00906575, 1.00621605, 2.99699807, 3.01898813, -0.00587920891, -0.00130371447, 0.265483797, -0.055073604, 0.011973233, -0.134105235, 0.0251861271, 9.57183802e-05, 1.00203371, 1.00308764, 2.99510217, 3.01161313, -0.00545941154, 9.6393931e-05, -0.237764418}},
    {"fixed-q",
     {-0.169278011, 0.2279526, 0.24807775, 1.1830132, 0.251612186, 0.198903739, 0.0431474447, -0.522732258, -0.403907716},
     {0.0117591098, 0.0405286029, -0.644785583, 0.00520767225, -0.0175293777, 1.0007633, 0.992819369, 2.99047637, 3.01027822, -9.55511041e-06, 2.86845989e-05, -0.948715746, 0.0440150872, 0.0453155041, 0.012603201, 0.0134679601, -0.00982107595, 0.990509152, 0.989188254, 2.99150085, 3.01152682, -1.32273663e-05, 2.59592707e-05, 0.131898597, 0.0803544223, 0.0404476076, 0.553108156, 0.0336132273, -0.0092916023, 0.983451903, 0.99273175, 2.99000001, 3.01547194, -1.26835612e-05, 2.3221839e-05, 0.933951557}},
};

// |got - expected| within 1e-6 of the largest |expected| of the vector (at least 1): the outputs are sums of
// terms of the vector's scale, so a value near 0 carries their absolute round-off. (The fixed observation is
// robot-frame; a target-frame model, whose statistics are of turned rows, answers it with outputs in the
// hundreds.)
void expect_close(const std::vector<double>& got, const std::vector<double>& expected, const std::string& what) {
  ASSERT_EQ(got.size(), expected.size()) << what;
  double scale = 1.0;
  for (const double e : expected) scale = std::max(scale, std::abs(e));
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], expected[i], 1e-6 * scale) << what << " value " << i;
}

}  // namespace

TEST(ShippedModels, ComputeWhatTheyComputedWhenShipped) {
  for (const Golden& golden : kGolden) {
    SCOPED_TRACE(golden.name);
    policy::Model model = policy::Model::load(kModels + golden.name + ".safetensors");
    ASSERT_EQ(model.network().outputs, 252);  // kColumns assume the default layout
    const Golden got = compute(model);
    expect_close(got.features, golden.features, "features");
    expect_close(got.outputs, golden.outputs, "decoder outputs");
  }
}
