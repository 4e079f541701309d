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

// Recorded with policy/model.cpp at 2e97193 (float32 inference, -march=native, printed with %.9g); each model
// again when it was replaced.
const Golden kGolden[] = {
    {"cvae",  // the DAgger model shipped on 2026-12-01 (target frame), recorded then the same way
     {0.138563961, -0.111075193, -0.00734755443, 0.0326534994, -0.0488756187, -0.111048594, 0.283747792, -0.103860572, -0.222432509},
     {-168.504898, -2.66895723, -77.1867981, 6.30964613, -5.88596773, -94.3580627, -65.9406204, 833.453125, 592.569885, -0.00409817649, 0.0153049249, -10.2498636, -169.176697, -2.64901257, -76.8005905, 6.31129932, -5.87616444, -94.296669, -65.8981018, 832.981689, 592.179138, -0.00410254439, 0.0153069757, -10.1861849, -169.848465, -2.62907195, -76.4142914, 6.31295443, -5.86635637, -94.2353592, -65.8555603, 832.510315, 591.788574, -0.00410692068, 0.0153090237, -10.12251}},
    {"bc",  // the DAgger bc shipped on 2026-12-01 (target frame, step 1500), recorded then the same way
     {0.230068862, -0.00866601616, -0.291621834, -0.155381754, 0.503598213, -0.0860742256, 0.144144133, 0.0299203154, 0.000670643058},
     {36.5927353, -9.33173084, 13.3510199, -4.35658312, -3.25932384, -0.897069812, 0.84848237, 2.52754164, 0.821321487, 0.00291560986, 0.320107788, -152.198486, 36.672699, -9.33112431, 13.3175821, -4.35581875, -3.2733078, -0.910705924, 0.844326377, 2.52620363, 0.815983295, 0.00336334691, 0.320002139, -151.25592, 36.752655, -9.33051395, 13.2841253, -4.35506105, -3.2872889, -0.924340367, 0.840168834, 2.52486324, 0.81064558, 0.00381114148, 0.3198964, -150.313339}},
    {"fixed-q",  // the DAgger fixed-q shipped on 2026-12-01 (target frame, step 250), the same way
     {0.195469618, 0.0557031594, -0.240142822, -0.240651801, 0.00383009762, 0.146472156, 0.08957012, -0.0043191202, 0.0504749455},
     {2.52070069, -5.41892767, -128.44516, 1.10032308, 0.424019933, -4.6165905, 1.86285913, -0.104735136, 7.02368259, 0.00141298759, -0.00353382109, -273.642731, 2.52904177, -5.41987801, -127.877083, 1.10010445, 0.437417656, -4.62232018, 1.85890973, -0.104349852, 7.02298594, 0.00141616119, -0.00351774995, -272.857239, 2.53478026, -5.4198823, -127.309265, 1.09959507, 0.451295286, -4.62851048, 1.85511684, -0.103860378, 7.02226591, 0.00141945912, -0.00350100803, -272.06488}},
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
