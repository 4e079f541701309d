// The folded networks and workspaces behind policy::Model (private to src/policy): model_load.cpp folds a
// checked model file into them, model_inference.cpp runs them.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "gemm.hpp"
#include "occtrack/policy/model.hpp"

namespace occtrack::policy {

namespace detail {

// A linear layer y = W x + b in double while folding; W is [out, in] as in torch.
struct Linear {
  Eigen::MatrixXd weight;
  Eigen::VectorXd bias;
};

// A folded layer in float, ready for the products.
struct Dense {
  Eigen::MatrixXf weight;  // out x in, column-major (gemm holds it packed for Eigen's blocked kernel)
  Eigen::VectorXf bias;
  Gemm gemm;

  Dense() = default;
  explicit Dense(const Linear& l) : weight(l.weight.cast<float>()), bias(l.bias.cast<float>()), gemm(weight) {}
  Eigen::Index rows() const { return weight.rows(); }
};

}  // namespace detail

struct Model::Impl {
  using Dense = detail::Dense;

  std::string source;
  Variant variant = Variant::cvae;
  NetworkConfig network;
  OutputLayout layout{NetworkConfig{}};
  projection::Settings projection;
  bool has_rho = false;
  std::optional<core::TrackingBand> band;
  std::map<std::string, std::string> metadata;

  // Folded networks (float).
  std::vector<Dense> pointnet;  // 1x1 convolutions with batch norm; the first also normalises the cloud
  Dense pointnet_fc0, pointnet_fc1;
  Dense decoder_latent;                  // the latent columns of decoder.fc0 (with its batch norm)
  Eigen::MatrixXf decoder_observation;   // its observation columns (input normalisation folded in)
  Eigen::MatrixXf decoder_features;      // its feature columns
  Eigen::VectorXf decoder_bias;
  std::vector<Dense> decoder_hidden;     // decoder.fc1 .. fc{L-1}
  Dense decoder_out;                     // output scale and offset folded in
  std::vector<Dense> encoder;            // encoder.fc0 .. fc{L-1}; fc0 normalises observation and xi
  Dense encoder_mean, encoder_std;

  // Workspaces.
  int max_batch = 0, max_points = 0;
  Eigen::VectorXf cloud_t;       // 2 x C, column-major
  Eigen::VectorXf ping, pong;    // widest layer x max(points, batch)
  Eigen::VectorXf pooled, pointnet_hidden, decoder_context;

  /// Folds a checked file's tensors (model_load.cpp).
  void fold(const io::ModelFile& file);
  /// Sizes the workspaces (model_inference.cpp).
  void reserve(int batch, int points);
};

}  // namespace occtrack::policy
