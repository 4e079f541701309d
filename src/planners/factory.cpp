#include <stdexcept>

#include "occtrack/planners/follower.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/planners/proj_cem.hpp"

namespace occtrack::planners {

std::vector<std::string> planner_names() { return {"projcem", "projcem-expert", "follower"}; }

std::unique_ptr<Planner> make_planner(const std::string& name, const PlannerOptions& options) {
  if (name == "projcem" || name == "projcem-expert") {
    ProjCemSettings s = name == "projcem-expert" || options.offline_expert
                            ? ProjCemSettings::offline_expert(options.threads)
                            : ProjCemSettings{};
    if (options.samples > 0) s.samples = options.samples;
    s.seed = options.seed;
    s.projection.threads = std::max(1, options.threads);
    return std::make_unique<ProjCem>(s);
  }
  if (name == "follower") return std::make_unique<Follower>();
  std::string known;
  for (const auto& n : planner_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown planner \"" + name + "\" (known: " + known + ")");
}

}  // namespace occtrack::planners
