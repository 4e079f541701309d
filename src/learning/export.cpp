#include "learning/export.hpp"

#include <nlohmann/json.hpp>

#include "learning/dataset.hpp"

namespace occtrack::learning {

namespace {

nlohmann::json loss_json(const LossTerms& l) {
  return {{"total", l.total}, {"mse", l.mse}, {"kl", l.kl}, {"residual", l.residual}};
}

}  // namespace

std::string training_json(const TrainingRecord& r) {
  nlohmann::json datasets = nlohmann::json::array();
  int64_t rows = 0;
  for (const auto& f : r.datasets) {
    datasets.push_back({{"path", f.path}, {"rows", f.rows}});
    rows += f.rows;
  }
  nlohmann::json losses = {{"train", loss_json(r.final_loss)}};
  if (r.validation) losses["validation"] = loss_json(*r.validation);
  const nlohmann::json j = {{"datasets", datasets},
                            {"rows", rows},
                            {"train_rows", r.train_rows},
                            {"validation_rows", r.validation_rows},
                            {"seed", r.seed},
                            {"steps", r.steps},
                            {"batch", r.batch},
                            {"learning_rate", r.learning_rate},
                            {"learning_rate_final", r.learning_rate_final},
                            {"beta", r.beta},
                            {"kl_warmup_steps", r.kl_warmup_steps},
                            {"dropout", r.dropout},
                            {"iterations", r.iterations},
                            {"projection_backward", r.plain_projection ? "plain" : "fast"},
                            {"device", r.device},
                            {"hardware", r.hardware},
                            {"seconds", r.seconds},
                            {"final_losses", losses}};
  return j.dump();
}

std::string band_json(const core::TrackingBand& band) {
  return nlohmann::json{{"min", band.min}, {"reference", band.reference}, {"max", band.max}}.dump();
}

io::TensorFile model_file(CvaeImpl& model, const ModelMetadata& m) {
  io::TensorFile file;
  file.metadata["format"] = kModelFormat;
  file.metadata["variant"] = to_string(m.variant);
  file.metadata["network"] = network_json(m.network);
  nlohmann::json projection = nlohmann::json::parse(projection_json(m.projection));
  projection["training_iterations"] = m.projection.iterations;
  file.metadata["projection"] = projection.dump();
  file.metadata["band"] = band_json(m.band);
  file.metadata["training"] = training_json(m.training);
  file.metadata["created_by"] = m.created_by;
  torch::NoGradGuard no_grad;
  for (const auto& [name, tensor] : named_model_tensors(model)) {
    const torch::Tensor t = tensor.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    file.put_raw(name, io::DType::F32, t.sizes().vec(), t.data_ptr<float>());
  }
  return file;
}

void export_model(const std::string& path, CvaeImpl& model, const ModelMetadata& metadata) {
  io::write_safetensors(path, model_file(model, metadata));
}

}  // namespace occtrack::learning
