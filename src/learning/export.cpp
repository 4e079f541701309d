#include "learning/export.hpp"

#include <nlohmann/json.hpp>

namespace occtrack::learning {

namespace {

nlohmann::json loss_json(const LossTerms& l) {
  return {{"total", l.total}, {"mse", l.mse}, {"kl", l.kl}, {"residual", l.residual}};
}

}  // namespace

std::string training_json(const TrainingRecord& r) {
  nlohmann::json datasets = nlohmann::json::array();
  int64_t rows = 0, dagger_rounds = 0;
  for (const auto& f : r.datasets) {
    datasets.push_back({{"path", f.path}, {"rows", f.rows}, {"episodes", f.episodes}, {"driver", f.driver}});
    rows += f.rows;
    if (f.learned_driver) ++dagger_rounds;
  }
  nlohmann::json losses = {{"train", loss_json(r.final_loss)}};
  if (r.validation) losses["validation"] = loss_json(*r.validation);
  nlohmann::json j = {{"datasets", datasets},
                      {"rows", rows},
                      {"dagger_rounds", dagger_rounds},
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
  if (r.initial_model) {
    // The lineage: the initial model's own record, whole, and the rows and DAgger rounds of both trainings.
    nlohmann::json parent = nlohmann::json::parse(r.initial_model->training, nullptr, /*allow_exceptions=*/false);
    if (!parent.is_object()) parent = nlohmann::json::object();
    auto count = [&](const char* with_initial, const char* own) {
      const auto it = parent.contains(with_initial) ? parent.find(with_initial) : parent.find(own);
      return it != parent.end() && it->is_number_integer() ? it->get<int64_t>() : int64_t{0};
    };
    j["rows_with_initial"] = rows + count("rows_with_initial", "rows");
    j["dagger_rounds_with_initial"] = dagger_rounds + count("dagger_rounds_with_initial", "dagger_rounds");
    j["initial_model"] = {{"path", r.initial_model->path},
                          {"created_by", r.initial_model->created_by},
                          {"training", parent}};
  }
  return j.dump();
}

io::ModelFile model_file(CvaeImpl& model, const ModelMetadata& m) {
  io::ModelFile file;
  file.variant = m.variant;
  file.network = m.network;
  file.projection = m.projection;
  file.band = m.band;
  file.metadata["training"] = training_json(m.training);
  file.metadata["created_by"] = m.created_by;
  io::TensorFile tensors;
  torch::NoGradGuard no_grad;
  for (const auto& [name, tensor] : named_model_tensors(model)) {
    const torch::Tensor t = tensor.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    tensors.put_raw(name, io::DType::F32, t.sizes().vec(), t.data_ptr<float>());
  }
  file.tensors = std::move(tensors.tensors);
  return file;
}

void export_model(const std::string& path, CvaeImpl& model, const ModelMetadata& metadata) {
  io::write_model_file(path, model_file(model, metadata));
}

}  // namespace occtrack::learning
