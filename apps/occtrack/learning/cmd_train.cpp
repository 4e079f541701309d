// occtrack train --data FILE [--data FILE ...] --out MODEL.safetensors [--variant cvae|bc|fixed-q]
//                [--steps N] [--batch B] [--lr LR] [--beta BETA] [--iterations K] [--device cpu|cuda]
//                [--threads T] [--seed S] [--checkpoint FILE] [--checkpoint-every N] [--resume FILE]
//                [--snapshot-every N] [--init MODEL.safetensors]
//                [--hidden H] [--layers L] [--features F] [--pointnet-hidden HP] [--pointnet-widths W,...]
//                [--latent Z] [--dropout P] [--validation-share S] [--validation-every N] [--plain-projection]
//                [--loss-log FILE.csv] [--world-size W --rank R --rendezvous FILE|HOST:PORT]
//
// Data-parallel (docs/scaling.md): W processes, started by hand with --world-size, --rank and --rendezvous, or
// by mpirun / srun (rank and size from the launcher; --rendezvous still names where they meet), each compute
// their share of every batch; rank 0 prints, validates and writes checkpoints, snapshots and the model.
//
// Trains the policy end to end through the unrolled projection (shared/spec/policy.md, docs/learning.md) and
// writes the model file. Progress (step, loss terms, steps/s, ETA) goes to standard error every few
// seconds; the summary to standard output.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "../cli_support.hpp"
#include "../commands.hpp"
#include "../launcher.hpp"
#include "allocation.hpp"
#include "learning/dataset.hpp"
#include "learning/distributed.hpp"
#include "learning/export.hpp"
#include "learning/trainer.hpp"

namespace occtrack::app {

namespace {

struct TrainOptions {
  std::vector<std::string> data;
  std::string out;
  std::string variant = "cvae";
  std::string frame = "target";  // measured better than robot (docs/learning.md, "Target frame")
  std::string resume;
  int threads = 0;
  int64_t snapshot_every = 0;  ///< write the model every this many steps beside --out (0: only at the end)
  std::string loss_log;        ///< CSV of every step's loss terms (rank 0)
  int world_size = 0;          ///< 0: one process, or the launcher's size
  int rank = -1;               ///< -1: 0, or the launcher's rank
  learning::DistributedSettings distributed;
  learning::TrainingSettings settings;
};

/// Where the snapshot of `step` goes: --out with ".stepN" before its extension (model.safetensors ->
/// model.step1000.safetensors).
std::string snapshot_path(const std::string& out, int64_t step) {
  const std::string::size_type slash = out.find_last_of('/');
  const std::string::size_type dot = out.find_last_of('.');
  const bool has_extension = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  const std::string stem = has_extension ? out.substr(0, dot) : out;
  return stem + ".step" + std::to_string(step) + (has_extension ? out.substr(dot) : ".safetensors");
}

std::string duration_text(double seconds) {
  const long s = static_cast<long>(seconds + 0.5);
  char buffer[32];
  if (s >= 3600)
    std::snprintf(buffer, sizeof buffer, "%ldh%02ldm", s / 3600, (s / 60) % 60);
  else if (s >= 60)
    std::snprintf(buffer, sizeof buffer, "%ldm%02lds", s / 60, s % 60);
  else
    std::snprintf(buffer, sizeof buffer, "%lds", s);
  return buffer;
}

std::string loss_text(const learning::LossTerms& l) {
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "loss %.5g (mse %.4g, kl %.4g, residual %.4g)", l.total, l.mse, l.kl,
                l.residual);
  return buffer;
}

// The command as it could be typed again, for the model's created_by.
std::string canonical_command(const TrainOptions& o) {
  const auto& s = o.settings;
  std::ostringstream c;
  c << "occtrack train";
  for (const auto& d : o.data) c << " --data " << d;
  c << " --out " << o.out << " --variant " << o.variant << " --steps " << s.steps << " --batch " << s.batch
    << " --lr " << s.learning_rate << " --beta " << s.beta << " --iterations " << s.iterations << " --device "
    << s.device << " --seed " << s.seed << " --hidden " << s.network.hidden << " --layers " << s.network.layers
    << " --features " << s.network.features << " --pointnet-hidden " << s.network.pointnet_hidden
    << " --pointnet-widths ";
  for (std::size_t i = 0; i < s.network.pointnet_widths.size(); ++i)
    c << (i ? "," : "") << s.network.pointnet_widths[i];
  c << " --latent " << s.network.latent << " --dropout " << s.dropout << " --frame " << o.frame;
  if (s.learning_rate_final >= 0) c << " --lr-final " << s.learning_rate_final;
  if (s.max_seconds > 0) c << " --max-minutes " << s.max_seconds / 60.0;
  if (s.kl_warmup_steps != learning::TrainingSettings{}.kl_warmup_steps) c << " --kl-warmup " << s.kl_warmup_steps;
  if (!s.initial_model.empty()) c << " --init " << s.initial_model;
  if (s.plain_projection) c << " --plain-projection";
  if (o.distributed.world_size > 1) c << " --world-size " << o.distributed.world_size;
  if (!o.resume.empty()) c << " --resume " << o.resume;
  if (o.snapshot_every > 0) c << " --snapshot-every " << o.snapshot_every;
  return c.str();
}

int run(TrainOptions o) {
  const char* who = "occtrack train: ";
  keep_large_allocations();
  o.settings.variant = io::parse_variant(o.variant);
  o.settings.network.target_frame = o.frame == "target";
  if (o.settings.checkpoint_path.empty() && !o.resume.empty()) o.settings.checkpoint_path = o.resume;

  // Processes: the options, else the launcher's (mpirun, srun), else one.
  const std::optional<LauncherRanks> launcher = launcher_ranks();
  learning::DistributedSettings& d = o.distributed;
  d.world_size = o.world_size > 0 ? o.world_size : launcher ? launcher->size : 1;
  d.rank = o.rank >= 0 ? o.rank : launcher ? launcher->rank : 0;
  if (d.world_size > 1 && o.rank < 0 && !launcher) {
    std::cerr << who << "--rank: give each process its rank with --world-size " << d.world_size
              << " (or start them with mpirun, which numbers them)\n";
    return kExitInputError;
  }
  std::string error;
  if (!d.validate(&error)) {
    std::cerr << who << error << " (--world-size, --rank, --rendezvous)\n";
    return kExitInputError;
  }
  if (d.world_size > 1 && !learning::distributed_training_available()) {
    std::cerr << who << "--world-size " << d.world_size
              << ": this occtrack was built without LibTorch's Gloo backend (install libgloo-dev and build again)\n";
    return kExitInputError;
  }
  const bool reports = d.rank == 0;
  // Threads: as asked; else, under a launcher, the cores shared out among its processes on this machine and
  // no more than this one is bound to; else torch's default.
  learning::set_training_threads(o.threads > 0 ? o.threads
                                 : launcher     ? default_threads(true, launcher->local_size > 0 ? launcher->local_size : 1)
                                                : 0,
                                 /*shared=*/d.world_size > 1);

  learning::Dataset data = learning::load_dataset(o.data);
  std::shared_ptr<learning::ProcessGroup> group;
  if (d.world_size > 1) {
    if (reports)
      std::fprintf(stderr, "%swaiting for %d processes at %s\n", who, d.world_size, d.rendezvous.c_str());
    group = std::make_shared<learning::ProcessGroup>(d);
  }
  if (reports) std::fprintf(stderr, "%sloaded %lld rows from %zu file(s): cloud %lld points, %lld obstacle points, n = %d, m = %d\n",
               who, static_cast<long long>(data.rows()), data.files.size(), static_cast<long long>(data.cloud_points()),
               static_cast<long long>(data.nearest_points()), data.coefficients(), data.projection.steps);
  learning::Trainer trainer(o.settings, std::move(data), group);
  if (reports) std::fprintf(stderr, "%s%s (%s frame) on %s, %lld training rows (%lld episodes), %lld validation rows (%lld "
               "episodes), K = %d (%s projection backward)\n",
               who, io::to_string(o.settings.variant), o.frame.c_str(),
               learning::hardware_description(trainer.device()).c_str(),
               static_cast<long long>(trainer.split().train.numel()),
               static_cast<long long>(trainer.split().train_episodes),
               static_cast<long long>(trainer.split().validation.numel()),
               static_cast<long long>(trainer.split().validation_episodes), o.settings.iterations,
               o.settings.plain_projection ? "plain" : "fast");
  if (group && reports)
    std::fprintf(stderr, "%s%d processes, each %lld of every %lld rows, %d threads each\n", who, d.world_size,
                 static_cast<long long>(std::min<int64_t>(o.settings.batch, trainer.split().train.numel()) / d.world_size),
                 static_cast<long long>(std::min<int64_t>(o.settings.batch, trainer.split().train.numel())),
                 torch::get_num_threads());
  std::ofstream loss_log;
  if (reports && !o.loss_log.empty()) {
    loss_log.open(o.loss_log);
    if (!loss_log) {
      std::cerr << who << "--loss-log: cannot write '" << o.loss_log << "'\n";
      return kExitInputError;
    }
    loss_log << "step,total,mse,kl,residual,validation_total,validation_mse,validation_kl,validation_residual\n";
    loss_log.precision(9);
  }
  if (!o.resume.empty()) {
    trainer.load_checkpoint(o.resume);
    if (reports) std::fprintf(stderr, "%sresumed from %s at step %lld\n", who, o.resume.c_str(),
                 static_cast<long long>(trainer.current_step()));
  }

  const learning::TrainingSummary summary = trainer.run([&](const learning::TrainingProgress& p) {
    if (!reports) return;
    std::string line = "step " + std::to_string(p.step) + "/" + std::to_string(p.steps) + "  " + loss_text(p.loss);
    char rate[96];
    std::snprintf(rate, sizeof rate, "  %.2f steps/s  elapsed %s  ETA %s", p.steps_per_second,
                  duration_text(p.elapsed_seconds).c_str(), duration_text(p.eta_seconds).c_str());
    line += rate;
    if (p.validation) line += "  | validation " + loss_text(*p.validation);
    if (!p.checkpoint.empty()) line += "  | checkpoint " + p.checkpoint;
    std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  }, [&](int64_t step, const learning::TrainingSummary& so_far) {
    if (!reports) return;
    if (loss_log.is_open()) {
      const learning::LossTerms& l = so_far.history.back();
      loss_log << step << ',' << l.total << ',' << l.mse << ',' << l.kl << ',' << l.residual;
      if (so_far.validation && so_far.validation_step == step) {
        const learning::LossTerms& v = *so_far.validation;
        loss_log << ',' << v.total << ',' << v.mse << ',' << v.kl << ',' << v.residual;
      } else {
        loss_log << ",,,,";
      }
      loss_log << '\n';
    }
    // Snapshots for choosing a model in closed loop (docs/learning.md, "Choosing the model"): each a complete
    // model file, its metadata as at that step.
    if (o.snapshot_every <= 0 || step % o.snapshot_every != 0 || step >= o.settings.steps) return;
    learning::TrainingSummary at;
    at.steps = so_far.steps;
    at.seconds = so_far.seconds;
    at.final_loss = so_far.final_loss;
    at.validation = trainer.validate();
    const std::string path = snapshot_path(o.out, step);
    learning::export_model(path, *trainer.model(), trainer.model_metadata(at, created_by(canonical_command(o))));
    std::fprintf(stderr, "%ssnapshot at step %lld: %s%s\n", who, static_cast<long long>(step), path.c_str(),
                 at.validation ? ("  validation " + loss_text(*at.validation)).c_str() : "");
  });

  if (!reports) return kExitOk;  // rank 0 writes the model
  learning::export_model(o.out, *trainer.model(), trainer.model_metadata(summary, created_by(canonical_command(o))));
  std::printf("trained %s for %lld steps in %s: final %s\n", io::to_string(o.settings.variant),
              static_cast<long long>(summary.steps), duration_text(summary.seconds).c_str(),
              loss_text(summary.final_loss).c_str());
  if (summary.validation) std::printf("  validation %s\n", loss_text(*summary.validation).c_str());
  std::printf("  model %s\n", o.out.c_str());
  return kExitOk;
}

}  // namespace

void add_train_command(CLI::App& app, int& exit_code) {
  auto [cmd, o] = add_command<TrainOptions>(app, "train", "Train the learned policy end to end through the projection");
  auto& s = o->settings;
  cmd->add_option("--data", o->data, "Dataset file (occtrack.dataset.v1); repeat for several")->required();
  cmd->add_option("--out", o->out, "Model file to write (occtrack.model.v1 safetensors)")->required();
  add_choice_option(cmd, "--variant", o->variant, "cvae, bc (no projection) or fixed-q (nominal q)",
                    {"cvae", "bc", "fixed-q"});
  add_choice_option(cmd, "--frame", o->frame,
                    "What the networks see: target (robot-centric, turned so that the target lies on +x; the "
                    "default) or robot (robot-centric, world axes; the models shipped before issue 12)",
                    {"robot", "target"});
  add_bounded_option(cmd, "--steps", s.steps, "Optimisation steps in all (a resumed run continues up to this)",
                     int64_t{0}, int64_t{1} << 40);
  add_bounded_option(cmd, "--batch", s.batch, "Rows per mini-batch", int64_t{1}, int64_t{1} << 24);
  cmd->add_option("--lr", s.learning_rate, "Adam learning rate")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--lr-final", s.learning_rate_final,
                  "Learning rate at the last step, reached by cosine decay from --lr (default: constant --lr)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option_function<double>(
         "--max-minutes", [&s](double minutes) { s.max_seconds = 60.0 * minutes; },
         "Stop after this many minutes of training and write the model as at the last step (for fixed-time "
         "machines; the metadata records the steps done)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--beta", s.beta, "KL weight after the warm-up")->check(CLI::NonNegativeNumber)->capture_default_str();
  cmd->add_option("--kl-warmup", s.kl_warmup_steps, "Steps over which the KL weight ramps up to beta")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  add_bounded_option(cmd, "--iterations", s.iterations, "K, unrolled projection iterations in training", 1, 100000);
  cmd->add_flag("--plain-projection", s.plain_projection,
                "Differentiate through the plain torch loop (autograd) instead of the hand-written backward");
  cmd->add_option("--device", s.device, "cpu, cuda or cuda:I")->capture_default_str();
  add_bounded_option(cmd, "--threads", o->threads, "CPU threads for torch (0: torch's default)", 0, 1024);
  cmd->add_option("--seed", s.seed, "Seed of the weights, batches, latent noise and dropout")->capture_default_str();
  cmd->add_option("--checkpoint", s.checkpoint_path, "Checkpoint file (model and optimizer), written periodically");
  cmd->add_option("--checkpoint-every", s.checkpoint_every, "Steps between checkpoints")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--snapshot-every", o->snapshot_every,
                  "Also write the model every this many steps, as OUT with .stepN before the extension, for "
                  "choosing one in closed loop (scripts/validate_models.sh; 0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--init", s.initial_model,
                  "Start from this model file's weights and input normalisation instead of random weights "
                  "(fine-tuning, e.g. one more DAgger round on a shipped model; same variant, sizes and frame); "
                  "the new model's metadata records it under training.initial_model")
      ->check(CLI::ExistingFile);
  cmd->add_option("--resume", o->resume,
                  "Continue from this checkpoint (same data, variant, sizes, batch, seed and K); new checkpoints "
                  "go to --checkpoint, or to this file");
  add_bounded_option(cmd, "--hidden", s.network.hidden, "H, encoder and decoder width", 1, 1 << 16);
  add_bounded_option(cmd, "--layers", s.network.layers, "L, hidden layers of encoder and decoder", 1, 64);
  add_bounded_option(cmd, "--features", s.network.features, "F, PointNet output features", 1, 1 << 16);
  add_bounded_option(cmd, "--pointnet-hidden", s.network.pointnet_hidden, "H_p, PointNet fully connected width",
                     1, 1 << 16);
  cmd->add_option("--pointnet-widths", s.network.pointnet_widths, "PointNet per-point widths (the last is E)")
      ->delimiter(',')
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str();
  add_bounded_option(cmd, "--latent", s.network.latent, "Z, latent size", 1, 1024);
  add_bounded_option(cmd, "--dropout", s.dropout, "PointNet dropout probability", 0.0, 0.99);
  add_bounded_option(cmd, "--validation-share", s.validation_share, "Share of the episodes held out for validation",
                     0.0, 0.9);
  cmd->add_option("--validation-every", s.validation_every, "Steps between validation losses (0: at the end only)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--progress-seconds", s.progress_seconds, "Seconds between progress lines")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--loss-log", o->loss_log, "Write every step's loss terms to this CSV file (step, total, mse, kl, residual; then the validation "
                  "loss's at the steps it is computed)");
  add_bounded_option(cmd, "--world-size", o->world_size,
                     "Data-parallel: processes in all (default: the launcher's under mpirun or srun, else 1)", 1, 1 << 16);
  add_bounded_option(cmd, "--rank", o->rank, "Data-parallel: this process, 0 .. world size - 1 (rank 0 writes)", 0,
                     (1 << 16) - 1);
  cmd->add_option("--rendezvous", o->distributed.rendezvous,
                  "Data-parallel: where the processes meet: a FILE every process can open (fresh), or HOST:PORT "
                  "where rank 0 listens");
  cmd->add_option("--dist-timeout", o->distributed.timeout_seconds,
                  "Data-parallel: seconds to wait for the other processes (joining, each exchange)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  set_command_body(cmd, exit_code, [o] { return run(*o); });
}

}  // namespace occtrack::app
