// The Python module `occtrack._occtrack` (pybind11), wrapped by python/occtrack/__init__.py.
//
// A thin layer: planners, scenarios, episodes, datasets and models come from the run-time library, and an
// episode's settings are parsed by the command line's own option table (apps/occtrack/episode_common.hpp), so
// that `run_episode(path, latency=20)` accepts exactly what `occtrack run --latency 20` accepts, with the same
// messages. Arrays cross as NumPy arrays (copies: a planning cycle's arrays are small).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "../apps/occtrack/episode_common.hpp"
#include "occtrack/io/dataset_file.hpp"
#include "occtrack/io/html_replay.hpp"
#include "occtrack/io/model_file.hpp"
#include "occtrack/io/results.hpp"
#include "occtrack/io/safetensors.hpp"
#include "occtrack/io/scenario.hpp"
#include "occtrack/planners/planner.hpp"
#include "occtrack/sim/episode.hpp"
#include "occtrack/sim/paper_worlds.hpp"
#include "occtrack/sim/recorded_path.hpp"
#include "occtrack/sim/scenario_generator.hpp"

namespace py = pybind11;
using namespace occtrack;

namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// ---- NumPy in and out -------------------------------------------------------------------------------------

/// A 2-vector from any array-like of two finite numbers; ValueError naming `what` otherwise.
core::Vec2 vec2(const py::object& value, const char* what) {
  Array a;
  try {
    a = Array::ensure(value);
  } catch (const py::error_already_set&) {
  }
  if (!a || a.ndim() != 1 || a.shape(0) != 2)
    throw py::value_error(std::string(what) + ": must be an array of 2 numbers (x, y)");
  const core::Vec2 v(a.at(0), a.at(1));
  if (!v.allFinite()) throw py::value_error(std::string(what) + ": must be finite, got NaN or infinity");
  return v;
}

py::array_t<double> to_array(const core::Vec2& v) {
  py::array_t<double> a(2);
  a.mutable_at(0) = v.x();
  a.mutable_at(1) = v.y();
  return a;
}

/// Points as an (N, 2) array.
py::array_t<double> to_array(const std::vector<core::Vec2>& points) {
  py::array_t<double> a({static_cast<py::ssize_t>(points.size()), py::ssize_t{2}});
  auto m = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    m(i, 0) = points[i].x();
    m(i, 1) = points[i].y();
  }
  return a;
}

/// Candidates as an (M, N, 2) array when they all have N points (the planners' case), else a list.
py::object candidates_array(const std::vector<std::vector<core::Vec2>>& candidates) {
  const std::size_t n = candidates.empty() ? 0 : candidates.front().size();
  for (const auto& c : candidates)
    if (c.size() != n) {
      py::list list;
      for (const auto& each : candidates) list.append(to_array(each));
      return list;
    }
  py::array_t<double> a({static_cast<py::ssize_t>(candidates.size()), static_cast<py::ssize_t>(n), py::ssize_t{2}});
  auto m = a.mutable_unchecked<3>();
  for (std::size_t k = 0; k < candidates.size(); ++k)
    for (std::size_t i = 0; i < n; ++i) {
      m(k, i, 0) = candidates[k][i].x();
      m(k, i, 1) = candidates[k][i].y();
    }
  return a;
}

/// A safetensors file as ({name: array}, {key: value}).
py::tuple tensors_and_metadata(const io::TensorFile& file) {
  py::dict arrays;
  for (const auto& [name, t] : file.tensors) {
    std::vector<py::ssize_t> shape(t.shape.begin(), t.shape.end());
    py::dtype dtype;
    switch (t.dtype) {
      case io::DType::F32: dtype = py::dtype::of<float>(); break;
      case io::DType::F64: dtype = py::dtype::of<double>(); break;
      case io::DType::I32: dtype = py::dtype::of<std::int32_t>(); break;
      case io::DType::I64: dtype = py::dtype::of<std::int64_t>(); break;
    }
    py::array a(dtype, shape);
    std::memcpy(a.mutable_data(), t.bytes.data(), t.bytes.size());
    arrays[py::str(name)] = a;
  }
  py::dict metadata;
  for (const auto& [key, value] : file.metadata) metadata[py::str(key)] = value;
  return py::make_tuple(arrays, metadata);
}

// ---- settings as keyword arguments ------------------------------------------------------------------------

/// Keyword arguments as the command line's options: latency=20 is --latency 20, shield=False is --no-shield,
/// target_noise=(0.05, 0.1) is --target-noise 0.05,0.1. Parsed by the option table of `occtrack run`, so
/// values are checked, and refused with the same messages, as there. TypeError for an unknown name.
app::EpisodeCliOptions episode_options(const std::string& planner, const py::kwargs& settings) {
  app::EpisodeCliOptions options;
  CLI::App cli("occtrack");
  app::add_episode_options(&cli, options);
  std::vector<std::string> args{"--planner", planner};
  for (const auto& [key, value] : settings) {
    std::string name = py::str(key);
    for (char& c : name)
      if (c == '_') c = '-';
    if (py::isinstance<py::bool_>(value)) {
      // A switch: shield=True is --shield, last_plan=False is --no-last-plan; the default's side may have no
      // flag of its own (there is no --last-plan), and then there is nothing to pass.
      const bool on = value.cast<bool>();
      const bool has_on = cli.get_option_no_throw("--" + name) != nullptr;
      const bool has_off = cli.get_option_no_throw("--no-" + name) != nullptr;
      if (!has_on && !has_off)
        throw py::type_error("unknown setting '" + std::string(py::str(key)) + "' (or it is not a switch)");
      if (on ? has_on : has_off) args.push_back((on ? "--" : "--no-") + name);
      continue;
    }
    if (cli.get_option_no_throw("--" + name) == nullptr)
      throw py::type_error("unknown setting '" + std::string(py::str(key)) + "'");
    std::string text;
    if (py::isinstance<py::tuple>(value) || py::isinstance<py::list>(value)) {
      for (const auto& item : value) {
        if (!text.empty()) text += ',';
        text += std::string(py::str(item));
      }
    } else {
      text = py::str(value);
    }
    args.push_back("--" + name);
    args.push_back(text);
  }
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes the arguments last first
  try {
    cli.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw py::value_error(e.what());
  }
  return options;
}

// ---- planners ---------------------------------------------------------------------------------------------

class PyPlanner {
 public:
  PyPlanner(const std::string& name, const py::kwargs& settings) {
    const app::EpisodeCliOptions options = episode_options(name, settings);
    // A planner alone has no replayed scans to time itself on: its latency is the caller's to know.
    if (options.latency_auto())
      throw py::value_error("--latency auto: a Planner cannot measure its own latency; give it in ms (latency=20)");
    planner_ = planners::make_planner(options.planner, options.planner_settings());
  }

  std::string name() const { return planner_->name(); }
  void reset() { planner_->reset(); }

  py::dict plan(const py::object& robot_position, const py::object& robot_velocity, const py::object& target_position,
                const py::object& target_velocity, const py::object& ranges, const py::object& angles,
                double angle_min, std::optional<double> angle_increment, double range_max, double time,
                double target_age) {
    planners::PlannerInput input;
    input.robot_position = vec2(robot_position, "robot_position");
    input.robot_velocity = vec2(robot_velocity, "robot_velocity");
    input.target_position = vec2(target_position, "target_position");
    input.target_velocity = vec2(target_velocity, "target_velocity");
    if (!std::isfinite(time)) throw py::value_error("time: must be finite");
    if (std::isnan(target_age) || target_age < 0.0) throw py::value_error("target_age: must be >= 0 (inf: never seen)");
    input.time = time;
    input.target_age = target_age;

    Array r;
    try {
      r = Array::ensure(ranges);
    } catch (const py::error_already_set&) {
    }
    if (!r || r.ndim() != 1 || r.shape(0) < 1)
      throw py::value_error("ranges: must be a 1-D array of at least one range (m), got " +
                            (r ? std::to_string(r.ndim()) + "-D" : std::string("no array")));
    scan_.ranges.assign(r.data(), r.data() + r.shape(0));
    for (std::size_t i = 0; i < scan_.ranges.size(); ++i)
      if (std::isnan(scan_.ranges[i]) || scan_.ranges[i] < 0.0)
        throw py::value_error("ranges: beam " + std::to_string(i) +
                              " is NaN or negative (a beam with no return is inf)");
    double increment = angle_increment.value_or(2.0 * std::numbers::pi / static_cast<double>(r.shape(0)));
    if (!angles.is_none()) {
      // One angle per beam, evenly spaced (a core::Scan is); they replace angle_min and angle_increment.
      Array a;
      try {
        a = Array::ensure(angles);
      } catch (const py::error_already_set&) {
      }
      if (!a || a.ndim() != 1 || a.shape(0) != r.shape(0))
        throw py::value_error("angles: must be a 1-D array with one angle per range (" +
                              std::to_string(r.shape(0)) + ")");
      const py::ssize_t n = a.shape(0);
      angle_min = a.at(0);
      increment = n > 1 ? (a.at(n - 1) - a.at(0)) / static_cast<double>(n - 1) : increment;
      for (py::ssize_t i = 0; i < n; ++i)
        if (!(std::abs(a.at(i) - (angle_min + static_cast<double>(i) * increment)) <= 1e-6))
          throw py::value_error("angles: must be finite and evenly spaced (beam " + std::to_string(i) + ")");
    }
    if (!std::isfinite(angle_min)) throw py::value_error("angle_min: must be finite");
    if (!(std::isfinite(increment) && increment > 0.0)) throw py::value_error("angle_increment: must be > 0");
    if (!(std::isfinite(range_max) && range_max > 0.0)) throw py::value_error("range_max: must be > 0");
    scan_.angle_min = angle_min;
    scan_.angle_increment = increment;
    scan_.range_max = range_max;
    scan_.time = time;
    input.scan = &scan_;

    {
      py::gil_scoped_release release;
      planner_->plan(input, out_);
    }
    py::dict result;
    result["command"] = to_array(out_.command_velocity);
    result["plan"] = to_array(out_.plan);
    result["candidates"] = candidates_array(out_.candidates);
    result["ok"] = out_.ok;
    result["message"] = out_.message;
    result["safety"] = std::string(planners::to_string(out_.safety));
    result["beyond_envelope"] = out_.beyond_envelope;
    result["compute_ms"] = out_.compute_ms;
    return result;
  }

 private:
  std::unique_ptr<planners::Planner> planner_;
  core::Scan scan_;
  planners::PlannerOutput out_;
};

// ---- scenarios and episodes -------------------------------------------------------------------------------

py::dict obstacle_dict(const core::ObstacleSpec& o) {
  py::dict d;
  d["shape"] = o.shape == core::ObstacleSpec::Shape::circle ? "circle" : "box";
  d["center"] = to_array(o.center);
  if (o.shape == core::ObstacleSpec::Shape::circle) {
    d["radius"] = o.radius;
  } else {
    d["size"] = to_array(o.size);
    d["yaw"] = o.yaw;
  }
  if (o.moving()) {
    d["path"] = to_array(o.path);
    d["speed"] = o.speed;
  }
  return d;
}

core::Scenario scenario_of(const py::object& scenario) {
  if (py::isinstance<core::Scenario>(scenario)) return scenario.cast<core::Scenario>();
  const std::string path = py::str(py::module_::import("os").attr("fspath")(scenario));
  return io::read_scenario(path);
}

// A recorded target path, (N, 3) rows of time, x, y, as a scenario in `world` (a Scenario, a paper world's
// name, or a scenario file), as `occtrack scenario import` makes it; warns (UserWarning) where the target
// overlaps obstacles or the robot's start does not see it.
core::Scenario scenario_from_path(const py::object& world, const Array& path, double period,
                                  std::optional<double> from_time, std::optional<double> to_time,
                                  std::optional<std::array<double, 2>> robot_start,
                                  std::optional<std::array<double, 3>> frame, const std::string& name) {
  if (path.ndim() != 2 || path.shape(1) != 3)
    throw std::invalid_argument("scenario_from_path: path must be an (N, 3) array of time, x, y");
  std::vector<core::TargetWaypoint> samples(static_cast<std::size_t>(path.shape(0)));
  const auto rows = path.unchecked<2>();
  for (py::ssize_t i = 0; i < path.shape(0); ++i)
    samples[static_cast<std::size_t>(i)] = {rows(i, 0), core::Vec2(rows(i, 1), rows(i, 2))};
  core::Scenario layout;
  if (py::isinstance<py::str>(world)) {
    const std::optional<core::Scenario> paper = sim::paper_world(world.cast<std::string>());
    layout = paper ? *paper : scenario_of(world);
  } else {
    layout = scenario_of(world);
  }
  sim::RecordedPathSettings settings;
  settings.period = period;
  if (from_time) settings.from = *from_time;
  if (to_time) settings.to = *to_time;
  if (robot_start) settings.robot_start = core::Vec2((*robot_start)[0], (*robot_start)[1]);
  if (frame) {
    if (!(std::abs((*frame)[2]) <= 360.0))  // the settings' own check would speak of radians
      throw std::invalid_argument("scenario_from_path: frame's angle (" + std::to_string((*frame)[2]) +
                                  " degrees) must be within [-360, 360]");
    settings.offset = core::Vec2((*frame)[0], (*frame)[1]);
    settings.rotation = (*frame)[2] * std::numbers::pi / 180.0;
  }
  sim::RecordedPathReport report;
  core::Scenario s = sim::scenario_from_recorded_path(layout, samples, settings, name, &report);
  if (report.overlap_time > 0.0) {
    const std::string message = "the target's disk overlaps an obstacle for " + std::to_string(report.overlap_time) +
                                " s of the path, first at t = " + std::to_string(report.first_overlap) +
                                " s: is the path in this world's frame?";
    if (PyErr_WarnEx(PyExc_UserWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  }
  if (!report.robot_sees_target &&
      PyErr_WarnEx(PyExc_UserWarning, "the robot's start does not see the target's", 1) != 0)
    throw py::error_already_set();
  return s;
}

py::dict trace_dict(const core::Trace& trace) {
  py::dict d;
  d["time"] = py::array_t<double>(static_cast<py::ssize_t>(trace.time.size()), trace.time.data());
  d["robot"] = to_array(trace.robot);
  d["target"] = to_array(trace.target);
  py::array_t<bool> occluded(static_cast<py::ssize_t>(trace.occluded.size()));
  for (std::size_t i = 0; i < trace.occluded.size(); ++i) occluded.mutable_at(i) = trace.occluded[i] != 0;
  d["occluded"] = occluded;
  return d;
}

py::dict run_episode(const py::object& scenario_or_path, const std::string& planner, const py::object& html,
                     const py::kwargs& settings) {
  const core::Scenario scenario = scenario_of(scenario_or_path);
  const app::EpisodeCliOptions options = episode_options(planner, settings);
  sim::EpisodeResult result;
  {
    py::gil_scoped_release release;
    sim::EpisodeSettings episode = app::resolve_episode_settings(options, {scenario});
    episode.record_cycles = !html.is_none();  // as `occtrack run --html`
    auto p = planners::make_planner(options.planner, options.planner_settings(&episode));
    result = sim::run_episode(scenario, *p, episode);
  }
  if (!html.is_none()) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(html));
    std::ofstream out(path, std::ios::binary);
    out << io::episode_html(scenario, result.trace, result.metrics);
    if (!out) throw io::InputError(path + ": cannot write the file");
  }
  // The metrics under the spec's keys: the JSON `occtrack run --json` writes, read back.
  py::dict metrics = py::module_::import("json").attr("loads")(io::episode_json(result.metrics));
  metrics["trace"] = trace_dict(result.trace);
  return metrics;
}

std::vector<core::Scenario> suite_scenarios(const std::string& name, std::optional<std::uint64_t> seed,
                                            std::optional<int> episodes, std::optional<double> duration) {
  std::optional<sim::SuiteSpec> spec = sim::find_suite(name);
  if (!spec) {
    std::string names;
    for (const auto& s : sim::benchmark_suites()) names += " " + s.name;
    for (const auto& s : sim::benchmark_suites_v2()) names += " " + s.name;
    throw py::value_error("suite: unknown suite '" + name + "'; one of:" + names);
  }
  // As `occtrack scenario generate --suite NAME [--seed S] [--episodes N] [--duration D]`.
  if (seed) spec->episode_seed_base = *seed;
  if (episodes) {
    if (*episodes < 1) throw py::value_error("episodes: must be >= 1");
    spec->episodes_per_world = *episodes;
    for (sim::SuiteWorld& w : spec->worlds) w.episodes = 0;
  }
  if (duration) {
    if (!(std::isfinite(*duration) && *duration > 0.0)) throw py::value_error("duration: must be > 0 s");
    spec->target.duration = *duration;
  }
  return sim::suite_scenarios(*spec);
}

}  // namespace

PYBIND11_MODULE(_occtrack, m) {
  m.doc() = "occtrack: occlusion-aware target tracking (the C++ library's Python bindings)";
  py::register_exception<io::InputError>(m, "InputError", PyExc_ValueError);

  m.def("planner_names", &planners::planner_names, "Names accepted by Planner(name) and run_episode(planner=...)");

  py::class_<PyPlanner>(m, "Planner", "A planner by name; keyword settings as `occtrack run`'s options")
      .def(py::init<const std::string&, const py::kwargs&>(), py::arg("name"))
      .def_property_readonly("name", &PyPlanner::name)
      .def("reset", &PyPlanner::reset, "Forget warm starts and estimates (a new episode)")
      .def("plan", &PyPlanner::plan, py::kw_only(), py::arg("robot_position"), py::arg("robot_velocity"),
           py::arg("target_position"), py::arg("target_velocity"), py::arg("ranges"), py::arg("angles") = py::none(), py::arg("angle_min") = 0.0,
           py::arg("angle_increment") = py::none(), py::arg("range_max") = 10.0, py::arg("time") = 0.0,
           py::arg("target_age") = 0.0,
           "One planning cycle. Positions and velocities in the world frame; the scan's angles in the world "
           "frame's orientation: `angles` (one per beam, evenly spaced), or angle_min and angle_increment (which "
           "defaults to 360 degrees over the beams); inf: no return. "
           "Returns {command, plan (N, 2), candidates (M, N, 2), ok, message, safety, beyond_envelope, compute_ms}; "
           "beyond_envelope: the safety layer's estimates show moving obstacles faster than its moving_speed_max "
           "(if they are, raise it).");

  py::class_<core::Scenario>(m, "Scenario", "A scenario (occtrack.scenario.v1)")
      .def_readonly("name", &core::Scenario::name)
      .def_readonly("duration", &core::Scenario::duration)
      .def_readonly("robot_radius", &core::Scenario::robot_radius)
      .def_readonly("target_radius", &core::Scenario::target_radius)
      .def_property_readonly("robot_position", [](const core::Scenario& s) { return to_array(s.robot_position); })
      .def_property_readonly("robot_velocity", [](const core::Scenario& s) { return to_array(s.robot_velocity); })
      .def_property_readonly("target",
                             [](const core::Scenario& s) {
                               py::array_t<double> a({static_cast<py::ssize_t>(s.target.size()), py::ssize_t{3}});
                               auto w = a.mutable_unchecked<2>();
                               for (std::size_t i = 0; i < s.target.size(); ++i) {
                                 w(i, 0) = s.target[i].time;
                                 w(i, 1) = s.target[i].position.x();
                                 w(i, 2) = s.target[i].position.y();
                               }
                               return a;
                             },
                             "The target's waypoints: (K, 3) rows of time, x, y")
      .def_property_readonly("obstacles",
                             [](const core::Scenario& s) {
                               py::list list;
                               for (const auto& o : s.obstacles) list.append(obstacle_dict(o));
                               return list;
                             })
      .def_property_readonly("sensor",
                             [](const core::Scenario& s) {
                               py::dict d;
                               d["beams"] = s.sensor.beams;
                               d["range"] = s.sensor.range;
                               d["noise"] = s.sensor.noise;
                               d["dropout"] = s.sensor.dropout;
                               return d;
                             })
      .def("to_yaml", [](const core::Scenario& s) { return io::scenario_yaml(s); })
      .def("__repr__", [](const core::Scenario& s) {
        return "<occtrack.Scenario '" + s.name + "', " + std::to_string(s.obstacles.size()) + " obstacles, " +
               std::to_string(s.duration) + " s>";
      });

  m.def("load_scenario", [](const py::object& path) { return scenario_of(path); }, py::arg("path"),
        "Reads and validates a scenario file");
  m.def("parse_scenario", &io::parse_scenario, py::arg("yaml_text"), py::arg("source") = "scenario",
        "A scenario from YAML text");
  m.def("scenario_from_path", &scenario_from_path, py::arg("world"), py::arg("path"), py::kw_only(),
        py::arg("period") = 0.1, py::arg("from_time") = py::none(), py::arg("to_time") = py::none(),
        py::arg("robot_start") = py::none(), py::arg("frame") = py::none(), py::arg("name") = "recorded",
        "A scenario of a recorded target path ((N, 3) rows of time, x, y in the world's frame) in `world`: "
        "'six-wall', 'six-wall-sliding', 'random', a Scenario or a scenario file. As `occtrack scenario import`: "
        "the samples from from_time to to_time, from t = 0, resampled every `period` s (0: every sample), the "
        "robot 2 m behind the target's start unless robot_start=(x, y); frame=(x, y, deg) places a path recorded "
        "in another frame (a sample p at R(deg) p + (x, y)); warns when the target overlaps obstacles "
        "(scenarios/README.md, \"Your own recorded target paths\")");
  m.def("suite_names", [] {
    std::vector<std::string> names;
    for (const auto& s : sim::benchmark_suites()) names.push_back(s.name);
    for (const auto& s : sim::benchmark_suites_v2()) names.push_back(s.name);
    return names;
  });
  m.def("suite_scenarios", &suite_scenarios, py::arg("suite"), py::kw_only(), py::arg("seed") = py::none(),
        py::arg("episodes") = py::none(), py::arg("duration") = py::none(),
        "A benchmark suite's scenarios, as `occtrack scenario generate --suite` writes them");

  m.def("run_episode", &run_episode, py::arg("scenario"), py::kw_only(), py::arg("planner") = "cvae",
        py::arg("html") = py::none(),
        "One closed-loop episode: the metrics under the spec's keys, and the trace under 'trace'; html=PATH "
        "also writes the replay page, as `occtrack run --html`");

  m.def("load_tensors", [](const std::string& path) { return tensors_and_metadata(io::read_safetensors(path)); },
        py::arg("path"), "Any safetensors file: ({name: array}, {key: value})");
  m.def("load_dataset",
        [](const std::string& path) {
          const io::TensorFile file = io::read_safetensors(path);  // read once, then
          io::validate_dataset_file(file);  // validated: the same errors as `occtrack train`
          return tensors_and_metadata(file);
        },
        py::arg("path"), "A dataset (occtrack.dataset.v1), validated: ({column: array}, metadata)");
  m.def("load_model",
        [](const std::string& path) {
          const io::TensorFile file = io::read_safetensors(path);
          io::validate_model_file(file);
          return tensors_and_metadata(file);
        },
        py::arg("path"), "A model file, validated: ({tensor: array}, metadata)");
}
