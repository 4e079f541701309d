#include "learning/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <dlfcn.h>
#include <unistd.h>
#include <fstream>
#include <stdexcept>

#include "learning/export.hpp"
#include "occtrack/io/projection_case.hpp"
#include "occtrack/sim/demonstrations.hpp"

namespace occtrack::learning {

using torch::indexing::Slice;

bool TrainingSettings::validate(std::string* error) const {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return false;
  };
  if (steps < 0) return fail("steps (" + std::to_string(steps) + ") must not be negative");
  if (batch <= 0) return fail("batch (" + std::to_string(batch) + ") must be positive");
  if (!(learning_rate > 0)) return fail("learning_rate must be positive");
  if (!(learning_rate_final < 0 || learning_rate_final <= learning_rate))
    return fail("learning_rate_final must not exceed learning_rate (negative: constant)");
  if (!(max_seconds >= 0)) return fail("max_seconds must not be negative");
  if (!(beta >= 0)) return fail("beta must not be negative");
  if (iterations <= 0) return fail("iterations (" + std::to_string(iterations) + ") must be positive");
  if (!(validation_share >= 0 && validation_share < 1)) return fail("validation_share must be in [0, 1)");
  if (validation_every < 0 || checkpoint_every < 0) return fail("validation_every and checkpoint_every must not be negative");
  if (!(band.min > 0 && band.min <= band.max)) return fail("band: need 0 < min <= max");
  std::string network_error;
  if (!network.validate(&network_error)) return fail("network: " + network_error);
  if (!(dropout >= 0 && dropout < 1)) return fail("dropout (" + std::to_string(dropout) + ") must be in [0, 1)");
  return true;
}

LossTerms& LossTerms::operator+=(const LossTerms& o) {
  total += o.total;
  mse += o.mse;
  kl += o.kl;
  residual += o.residual;
  return *this;
}

LossTerms LossTerms::operator/(double d) const { return {total / d, mse / d, kl / d, residual / d}; }

LossTerms LossTensors::values() const {
  auto value = [](const torch::Tensor& t) { return t.defined() ? t.item<double>() : 0.0; };
  return {value(total), value(mse), value(kl), value(residual)};
}

double learning_rate_at(double first, double final, int64_t step, int64_t steps) {
  if (final < 0 || steps <= 0) return first;
  const double t = std::min(1.0, static_cast<double>(step) / static_cast<double>(steps));
  return final + 0.5 * (first - final) * (1.0 + std::cos(3.14159265358979323846 * t));
}

double kl_weight(double beta, int64_t step, int64_t warmup_steps) {
  if (warmup_steps <= 0) return beta;
  return beta * std::min(1.0, static_cast<double>(step) / static_cast<double>(warmup_steps));
}

LossContext::LossContext(io::Variant variant, const projection::Settings& projection, const core::TrackingBand& band,
                         const io::NetworkConfig& network_config, int iterations_, bool plain, torch::Device device)
    : network(network_config), basis(projection, torch::kFloat32, device), iterations(iterations_),
      plain_projection(plain) {
  policy.variant = variant;
  policy.projection = projection;
  policy.projection.iterations = iterations_;
  policy.projection.obstacles = network_config.nearest_points;
  policy.band = band;
  if (variant != io::Variant::bc)
    constants = std::make_shared<ProjectionConstants>(policy.projection, torch::kFloat32, device);
}

LossTensors batch_loss(CvaeImpl& model, const Batch& batch, const LossContext& c, double beta_t,
                       const PassNoise* noise) {
  const CvaeForward f = model.forward(batch.observation, batch.cloud, batch.expert_xi, noise);
  const ProjectionInputs inputs =
      policy_outputs(f.outputs, batch.observation, batch.obstacles, c.policy, c.basis, c.network);
  LossTensors loss;
  torch::Tensor plan;
  if (c.policy.variant == io::Variant::bc) {
    plan = inputs.xi_bar;
    loss.residual = torch::zeros({}, plan.options());
  } else {
    const ProjectionOutputs out = c.plain_projection ? project_plain(*c.constants, inputs, c.iterations)
                                                     : project_fast(*c.constants, inputs, c.iterations);
    plan = out.xi;
    loss.residual = out.residual.mean();
  }
  loss.mse = (c.basis.positions(plan) - c.basis.positions(batch.expert_xi)).pow(2).mean();
  const Posterior& q = f.posterior;
  loss.kl = (0.5 * (q.mean.pow(2) + q.sigma.pow(2) - 1.0 - 2.0 * q.sigma.log())).sum(1).mean();
  loss.total = 0.5 * loss.mse + beta_t * loss.kl;
  if (c.policy.variant != io::Variant::bc) loss.total = loss.total + 0.5 * loss.residual;
  return loss;
}

// ---------------------------------------------------------------------------------------------------------

namespace {

torch::Device parse_device(const std::string& text) {
  torch::Device device(torch::kCPU);
  try {
    device = torch::Device(text);
  } catch (const std::exception&) {
    throw std::invalid_argument("device '" + text + "' is not cpu, cuda or cuda:I");
  }
  if (device.is_cuda() && !torch::cuda::is_available())
    throw std::runtime_error("device '" + text + "': CUDA is not available (this LibTorch was built without it, or "
                             "no GPU is visible)");
  if (!device.is_cpu() && !device.is_cuda()) throw std::invalid_argument("device '" + text + "' is not cpu or cuda");
  return device;
}

std::uint64_t mix(std::uint64_t a, std::uint64_t b) {  // splitmix64 of a combination
  std::uint64_t z = a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The fields a resumed run must share with the checkpoint: they change the loss trajectory.
std::string resume_identity(const TrainingSettings& s, const Dataset& data) {
  return std::string("variant=") + io::to_string(s.variant) + " network=" + s.network.to_json() +
         " dropout=" + std::to_string(s.dropout) + " batch=" + std::to_string(s.batch) +
         " seed=" + std::to_string(s.seed) + " iterations=" + std::to_string(s.iterations) +
         " rows=" + std::to_string(data.rows()) + " projection=" + io::projection_settings_json(data.projection);
}

/// FNV-1a of the settings that shape every step and of the data's values: what the processes of one
/// data-parallel training must share.
std::uint64_t training_fingerprint(const TrainingSettings& s, const Dataset& data) {
  std::string text = resume_identity(s, data);
  char numbers[256];
  std::snprintf(numbers, sizeof numbers, " steps=%lld lr=%.17g lr_final=%.17g beta=%.17g warmup=%lld share=%.17g",
                static_cast<long long>(s.steps), s.learning_rate, s.learning_rate_final, s.beta,
                static_cast<long long>(s.kl_warmup_steps), s.validation_share);
  text += numbers;
  for (const torch::Tensor& t : {data.observation, data.cloud, data.obstacles, data.expert_xi, data.episode}) {
    std::snprintf(numbers, sizeof numbers, " %.17g", t.to(torch::kFloat64).sum().item<double>());
    text += numbers;
  }
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

Trainer::Trainer(const TrainingSettings& settings, Dataset data, std::shared_ptr<ProcessGroup> group)
    : settings_(settings), data_(std::move(data)), device_(parse_device(settings.device)), group_(std::move(group)) {
  settings_.network.cloud_points = static_cast<int>(data_.cloud_points());
  settings_.network.nearest_points = static_cast<int>(data_.nearest_points());
  settings_.network.coefficients = data_.coefficients();
  settings_.network.steps = data_.projection.steps;
  settings_.network.outputs = settings_.network.expected_outputs();
  std::string error;
  if (!settings_.validate(&error)) throw std::invalid_argument("training settings: " + error);

  split_ = split_by_episode(data_, settings_.validation_share, settings_.seed);
  if (split_.train.numel() == 0) throw std::invalid_argument("training settings: no training rows");
  if (device_.is_cuda()) data_.to(device_);  // batches are gathered on the GPU

  reseed(-1);  // the initial weights depend on the seed alone
  model_ = Cvae(settings_.network, settings_.dropout);
  model_->set_normalization(compute_normalization(data_, split_.train, settings_.network, settings_.band));
  if (!settings_.initial_model.empty()) load_initial_model();
  model_->to(device_);
  optimizer_ = std::make_unique<torch::optim::Adam>(model_->parameters(),
                                                    torch::optim::AdamOptions(settings_.learning_rate));
  context_ = std::make_unique<LossContext>(settings_.variant, data_.projection, settings_.band, settings_.network,
                                           settings_.iterations, settings_.plain_projection, device_);
  sampler_ = std::make_unique<BatchSampler>(split_.train, settings_.batch, settings_.seed);

  if (distributed()) {
    if (std::min(settings_.batch, split_.train.numel()) < group_->size())
      throw std::invalid_argument("training settings: the batch (" + std::to_string(settings_.batch) +
                                  ", or the training rows) must hold at least one row per process (" +
                                  std::to_string(group_->size()) + ")");
    group_->require_same(training_fingerprint(settings_, data_), "the dataset or the training settings");
    // Identical by construction (same seed, same data); rank 0's copy is sent anyway, as DDP does.
    torch::NoGradGuard no_grad;
    for (torch::Tensor p : model_->parameters()) group_->broadcast(p);
    for (torch::Tensor b : model_->buffers()) group_->broadcast(b);
    ProcessGroup* g = group_.get();
    model_->set_batch_sum([g](const torch::Tensor& t) {
      torch::Tensor total = t.contiguous().clone();
      g->sum(total);
      return total;
    });
  }
}

void Trainer::load_initial_model() {
  const std::string& path = settings_.initial_model;
  const io::ModelFile file = io::read_model_file(path);
  if (file.variant != settings_.variant)
    throw std::invalid_argument("initial model " + path + ": it is a " + io::to_string(file.variant) +
                                " model, and this training's variant is " + io::to_string(settings_.variant));
  if (!(file.network == settings_.network))
    throw std::invalid_argument("initial model " + path + ": its network " + file.network.to_json() +
                                " differs from this training's " + settings_.network.to_json() +
                                " (the sizes of the options and of the data, and the frame, must match)");
  torch::NoGradGuard no_grad;
  for (auto& [name, tensor] : named_model_tensors(*model_)) {
    const std::vector<double> values = file.values(name);  // the file was checked: every tensor, its shape
    tensor.copy_(torch::tensor(values, torch::kFloat64).view(tensor.sizes()).to(tensor.dtype()));
  }
  auto meta = [&](const char* key) {
    const auto it = file.metadata.find(key);
    return it == file.metadata.end() ? std::string() : it->second;
  };
  initial_created_by_ = meta("created_by");
  initial_training_ = meta("training");
}

bool Trainer::distributed() const { return group_ && group_->size() > 1; }
bool Trainer::writes_files() const { return !group_ || group_->rank() == 0; }

void Trainer::reseed(int64_t stream) const {
  torch::manual_seed(mix(settings_.seed, static_cast<std::uint64_t>(stream)));
}

LossTerms Trainer::step() {
  reseed(step_);
  model_->train();
  // The step's global batch and its random draws are the same on every process; each takes its share of the
  // rows (contiguous, sizes differing by at most one).
  const torch::Tensor indices = sampler_->indices(step_);
  const int64_t rows = indices.numel();
  const int64_t parts = distributed() ? group_->size() : 1, part = distributed() ? group_->rank() : 0;
  const int64_t begin = rows * part / parts, end = rows * (part + 1) / parts;
  const PassNoise noise = PassNoise::draw(rows, settings_.network, settings_.dropout, device_);
  const PassNoise share_noise = noise.rows(begin, end);
  const Batch batch = data_.gather(indices.index({Slice(begin, end)}), device_);
  const double lr = learning_rate_at(settings_.learning_rate, settings_.learning_rate_final, step_, settings_.steps);
  for (auto& group : optimizer_->param_groups())
    static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
  optimizer_->zero_grad();
  const LossTensors loss = batch_loss(*model_, batch, *context_, kl_weight(settings_.beta, step_, settings_.kl_warmup_steps),
                                      &share_noise);
  LossTerms terms;
  if (!distributed()) {
    loss.total.backward();
    terms = loss.values();
  } else {
    // The loss terms are means over the rows: weighted by each share, their sum over the processes is the
    // global batch's mean, and so is the sum of the gradients.
    const double weight = static_cast<double>(end - begin) / static_cast<double>(rows);
    (loss.total * weight).backward();
    terms = sum_gradients(loss.values(), weight);
  }
  optimizer_->step();
  ++step_;
  return terms;
}

LossTerms Trainer::sum_gradients(const LossTerms& share, double weight) {
  // One all-reduce per step: every gradient, flattened, then the four weighted loss terms.
  std::vector<torch::Tensor> pieces;
  std::vector<torch::Tensor> parameters = model_->parameters();
  for (torch::Tensor& p : parameters) {
    if (!p.grad().defined()) p.mutable_grad() = torch::zeros_like(p);
    pieces.push_back(p.grad().reshape({-1}));
  }
  const auto options = torch::TensorOptions().dtype(torch::kFloat32).device(device_);
  pieces.push_back(torch::tensor({share.total * weight, share.mse * weight, share.kl * weight, share.residual * weight},
                                 torch::kFloat64)
                       .to(options));
  torch::Tensor flat = torch::cat(pieces);
  group_->sum(flat);
  int64_t offset = 0;
  torch::NoGradGuard no_grad;
  for (torch::Tensor& p : parameters) {
    const int64_t n = p.numel();
    p.mutable_grad().copy_(flat.index({Slice(offset, offset + n)}).view_as(p));
    offset += n;
  }
  const torch::Tensor loss = flat.index({Slice(offset, offset + 4)}).to(torch::kCPU, torch::kFloat64);
  const auto v = loss.accessor<double, 1>();
  return {v[0], v[1], v[2], v[3]};
}

std::optional<LossTerms> Trainer::validate() {
  if (split_.validation.numel() == 0) return std::nullopt;
  torch::NoGradGuard no_grad;
  reseed(-2);
  model_->eval();
  const torch::Tensor rows = split_.validation.index({Slice(0, settings_.validation_rows)});
  LossTerms sum;
  const double beta_t = kl_weight(settings_.beta, step_, settings_.kl_warmup_steps);
  for (int64_t begin = 0; begin < rows.numel(); begin += settings_.batch) {
    const torch::Tensor chunk = rows.index({Slice(begin, begin + settings_.batch)});
    const LossTerms terms = batch_loss(*model_, data_.gather(chunk, device_), *context_, beta_t).values();
    sum += LossTerms{terms.total * chunk.numel(), terms.mse * chunk.numel(), terms.kl * chunk.numel(),
                     terms.residual * chunk.numel()};
  }
  model_->train();
  return sum / static_cast<double>(rows.numel());
}

namespace {

/// The mean of the last (up to 100) steps' loss terms: a summary's final_loss.
LossTerms recent_mean(const std::vector<LossTerms>& history) {
  const std::size_t tail = std::min<std::size_t>(100, history.size());
  LossTerms sum;
  for (std::size_t i = history.size() - tail; i < history.size(); ++i) sum += history[i];
  return tail > 0 ? sum / static_cast<double>(tail) : sum;
}

}  // namespace

TrainingSummary Trainer::run(const std::function<void(const TrainingProgress&)>& progress,
                             const std::function<void(int64_t, const TrainingSummary&)>& after_step) {
  TrainingSummary summary;
  const auto start = Clock::now();
  const double elapsed_before = elapsed_seconds_;
  auto report_time = Clock::now();
  int64_t report_step = step_;
  LossTerms report_sum;
  TrainingProgress pending;
  auto elapsed = [&] { return elapsed_before + seconds_since(start); };

  while (step_ < settings_.steps) {
    const LossTerms terms = step();
    summary.history.push_back(terms);
    report_sum += terms;
    elapsed_seconds_ = elapsed();
    bool out_of_time = settings_.max_seconds > 0 && seconds_since(start) >= settings_.max_seconds;
    if (distributed() && settings_.max_seconds > 0) out_of_time = group_->any(out_of_time);  // all stop together
    const bool last = step_ == settings_.steps || out_of_time;
    // Validation and checkpoints: rank 0's (every process holds the same model).
    if (writes_files() && ((settings_.validation_every > 0 && step_ % settings_.validation_every == 0) || last))
      if (auto v = validate()) {
        pending.validation = v;
        summary.validation = v;
        summary.validation_step = step_;
      }
    if (writes_files() && !settings_.checkpoint_path.empty() &&
        ((settings_.checkpoint_every > 0 && step_ % settings_.checkpoint_every == 0) || last)) {
      save_checkpoint(settings_.checkpoint_path);
      pending.checkpoint = settings_.checkpoint_path;
    }
    if (after_step) {
      summary.steps = step_;
      summary.seconds = elapsed_seconds_;
      summary.final_loss = recent_mean(summary.history);
      after_step(step_, summary);
    }
    const double since = seconds_since(report_time);
    if (progress && (since >= settings_.progress_seconds || last)) {
      const int64_t done = step_ - report_step;
      pending.step = step_;
      pending.steps = settings_.steps;
      pending.loss = report_sum / static_cast<double>(std::max<int64_t>(1, done));
      pending.steps_per_second = since > 0 ? done / since : 0;
      pending.elapsed_seconds = elapsed_seconds_;
      pending.eta_seconds = pending.steps_per_second > 0 ? (settings_.steps - step_) / pending.steps_per_second : 0;
      progress(pending);
      pending = {};
      report_sum = {};
      report_step = step_;
      report_time = Clock::now();
    }
    if (out_of_time) break;
  }
  summary.steps = step_;
  summary.seconds = elapsed_seconds_;
  summary.final_loss = recent_mean(summary.history);
  if (summary.history.empty() && writes_files()) summary.validation = validate();  // resumed at the end
  return summary;
}

void Trainer::save_checkpoint(const std::string& path) const {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive model_archive, optimizer_archive;
  model_->save(model_archive);
  optimizer_->save(optimizer_archive);
  archive.write("model", model_archive);
  archive.write("optimizer", optimizer_archive);
  archive.write("step", c10::IValue(step_));
  archive.write("elapsed_seconds", c10::IValue(elapsed_seconds_));
  archive.write("identity", c10::IValue(resume_identity(settings_, data_)));
  // Write beside and rename, so that an interrupted save leaves the previous checkpoint intact.
  const std::string temporary = path + ".partial";
  archive.save_to(temporary);
  // (POSIX calls here and below rather than std::filesystem: LibTorch 2.x wheels export their own copies of
  // std::filesystem's symbols, which can interpose libstdc++'s.)
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
    throw std::runtime_error("checkpoint '" + path + "': " + std::strerror(errno));
}

void Trainer::load_checkpoint(const std::string& path) {
  if (::access(path.c_str(), F_OK) != 0) throw std::runtime_error("checkpoint '" + path + "' does not exist");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path, device_);
  } catch (const c10::Error& e) {
    throw std::runtime_error("checkpoint '" + path + "' cannot be read: " + e.what_without_backtrace());
  }
  c10::IValue identity, step, elapsed;
  if (!archive.try_read("identity", identity) || !archive.try_read("step", step) ||
      !archive.try_read("elapsed_seconds", elapsed))
    throw std::runtime_error("checkpoint '" + path + "' is not an occtrack training checkpoint");
  const std::string expected = resume_identity(settings_, data_);
  const std::string& found = identity.toStringRef();
  if (found != expected) {
    // Name the first field that differs.
    std::size_t i = 0;
    while (i < found.size() && i < expected.size() && found[i] == expected[i]) ++i;
    const std::size_t field = expected.rfind(' ', i) == std::string::npos ? 0 : expected.rfind(' ', i) + 1;
    const std::string name = expected.substr(field, expected.find('=', field) - field);
    throw std::runtime_error("checkpoint '" + path + "' was written with a different " + name + " (checkpoint: " +
                             found.substr(field, found.find(' ', field) - field) + ", now: " +
                             expected.substr(field, expected.find(' ', field) - field) + ")");
  }
  torch::serialize::InputArchive model_archive, optimizer_archive;
  archive.read("model", model_archive);
  archive.read("optimizer", optimizer_archive);
  model_->load(model_archive);
  optimizer_->load(optimizer_archive);
  step_ = step.toInt();
  elapsed_seconds_ = elapsed.toDouble();
}

int set_training_threads(int threads, bool shared) {
  if (threads > 0) torch::set_num_threads(threads);
  const int torch_threads = torch::get_num_threads();
  if ((torch_threads > 1 || shared) && std::getenv("OPENBLAS_NUM_THREADS") == nullptr) {
    // Looked up at run time: present only when the BLAS that LibTorch loaded is OpenBLAS.
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
  }
  return torch_threads;
}

ModelMetadata Trainer::model_metadata(const TrainingSummary& summary, const std::string& created_by) const {
  ModelMetadata m;
  m.variant = settings_.variant;
  m.network = settings_.network;
  m.projection = data_.projection;
  m.projection.iterations = settings_.iterations;
  m.projection.obstacles = settings_.network.nearest_points;
  m.band = settings_.band;
  m.created_by = created_by;
  TrainingRecord& t = m.training;
  for (const auto& f : data_.files) {
    const auto driver = f.metadata.find("driver");
    t.datasets.push_back({f.path, f.rows, f.episodes, driver == f.metadata.end() ? "" : driver->second,
                          sim::learned_driver(f.metadata)});
  }
  t.train_rows = split_.train.numel();
  t.validation_rows = split_.validation.numel();
  t.seed = settings_.seed;
  t.steps = summary.steps;
  t.batch = sampler_->batch();
  t.kl_warmup_steps = settings_.kl_warmup_steps;
  t.learning_rate = settings_.learning_rate;
  t.learning_rate_final = settings_.learning_rate_final < 0 ? settings_.learning_rate : settings_.learning_rate_final;
  t.beta = settings_.beta;
  t.dropout = settings_.dropout;
  t.iterations = settings_.iterations;
  t.plain_projection = settings_.plain_projection;
  t.device = device_.str();
  t.hardware = hardware_description(device_);
  t.seconds = summary.seconds;
  t.final_loss = summary.final_loss;
  t.validation = summary.validation;
  if (!settings_.initial_model.empty())
    t.initial_model = TrainingRecord::Initial{settings_.initial_model, initial_created_by_, initial_training_};
  return m;
}

// ---------------------------------------------------------------------------------------------------------

namespace {

std::string trim(std::string s) {
  const auto begin = s.find_first_not_of(" \t");
  const auto end = s.find_last_not_of(" \t\r\n");
  return begin == std::string::npos ? std::string() : s.substr(begin, end - begin + 1);
}

// The value of the first "key : value" line of a text file that starts with `key`.
std::string field_of(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return trim(line.substr(colon + 1));
    }
  return {};
}

}  // namespace

std::string hardware_description(torch::Device device) {
  if (device.is_cuda()) {
    // The driver's own description, one folder per GPU (ordered by bus id, as CUDA orders them by default).
    std::vector<std::string> folders;
    const std::string root = "/proc/driver/nvidia/gpus";
    if (DIR* d = ::opendir(root.c_str())) {
      while (const dirent* e = ::readdir(d))
        if (e->d_name[0] != '.') folders.push_back(root + "/" + e->d_name);
      ::closedir(d);
    }
    std::sort(folders.begin(), folders.end());
    const std::size_t index = device.has_index() ? static_cast<std::size_t>(device.index()) : 0;
    if (index < folders.size()) {
      const std::string model = field_of(folders[index] + "/information", "Model");
      if (!model.empty()) return model;
    }
    if (FILE* pipe = popen("nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null", "r")) {
      char buffer[256];
      std::vector<std::string> names;
      while (std::fgets(buffer, sizeof buffer, pipe)) names.push_back(trim(buffer));
      pclose(pipe);
      if (index < names.size() && !names[index].empty()) return names[index];
    }
    return "CUDA device " + std::to_string(index);
  }
  std::string model = field_of("/proc/cpuinfo", "model name");
  if (model.empty()) model = "unknown CPU";
  const int threads = torch::get_num_threads();
  return model + " (" + std::to_string(threads) + (threads == 1 ? " thread)" : " threads)");
}

}  // namespace occtrack::learning
