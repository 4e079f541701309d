#include "occtrack/io/projection_case.hpp"

#include <string>
#include <vector>

#include "json_util.hpp"

namespace occtrack::io {

namespace {

using detail::json;
using detail::JsonReader;
using projection::RowMatrix;

std::string at(const std::string& path, std::size_t i) { return path + "[" + std::to_string(i) + "]"; }

// A [B][cols] list of finite numbers; B fixed by the caller (batch < 0: taken from this list).
RowMatrix<double> read_rows(const JsonReader& r, const json& value, const std::string& path, int& batch, int cols) {
  if (!value.is_array()) r.fail(path, "must be a list with one entry per sample");
  if (batch < 0) {
    if (value.empty()) r.fail(path, "must hold at least one sample");
    batch = static_cast<int>(value.size());
  }
  if (static_cast<int>(value.size()) != batch)
    r.fail(path, "expected " + std::to_string(batch) + " samples (the batch size of inputs.robot_velocity), got " +
                     std::to_string(value.size()));
  // Rows are read before the matrix is sized: B and cols come from elsewhere in the file (B up to 10^6,
  // cols up to 10^4), and a list of B empty rows must not allocate B x cols numbers before it is refused.
  std::vector<double> values;
  for (int b = 0; b < batch; ++b) {
    const std::vector<double> row = r.numbers(value[b], at(path, b), cols);
    values.insert(values.end(), row.begin(), row.end());
  }
  return Eigen::Map<const RowMatrix<double>>(values.data(), batch, cols);
}

projection::Settings read_settings(const JsonReader& r, const json& config, const std::string& p, bool strict) {
  if (strict)
    r.only_keys(config, p,
                {"degree", "steps", "horizon", "iterations", "obstacle_radius", "speed_min", "speed_max", "accel_max",
                 "via_steps", "rho"});
  projection::Settings s;
  s.degree = r.integer(r.member(config, p, "degree"), p + ".degree");
  s.steps = r.integer(r.member(config, p, "steps"), p + ".steps");
  s.horizon = r.number(r.member(config, p, "horizon"), p + ".horizon");
  if (strict || config.contains("iterations"))
    s.iterations = r.integer(r.member(config, p, "iterations"), p + ".iterations");
  s.obstacle_radius = r.number(r.member(config, p, "obstacle_radius"), p + ".obstacle_radius");
  s.speed_min = r.number(r.member(config, p, "speed_min"), p + ".speed_min");
  s.speed_max = r.number(r.member(config, p, "speed_max"), p + ".speed_max");
  s.accel_max = r.number(r.member(config, p, "accel_max"), p + ".accel_max");
  const json& via = r.member(config, p, "via_steps");
  if (!via.is_array() || via.size() != 2) r.fail(p + ".via_steps", "must be a list of two step indices [s1, s2]");
  s.via_step_1 = r.integer(via[0], p + ".via_steps[0]");
  s.via_step_2 = r.integer(via[1], p + ".via_steps[1]");
  if (strict || config.contains("rho")) {
    const json& rho = r.member(config, p, "rho");
    const std::string q = p + ".rho";
    if (strict) r.only_keys(rho, q, {"obstacle", "velocity", "acceleration", "tracking", "projection"});
    s.rho.obstacle = r.number(r.member(rho, q, "obstacle"), q + ".obstacle");
    s.rho.velocity = r.number(r.member(rho, q, "velocity"), q + ".velocity");
    s.rho.acceleration = r.number(r.member(rho, q, "acceleration"), q + ".acceleration");
    s.rho.tracking = r.number(r.member(rho, q, "tracking"), q + ".tracking");
    s.rho.projection = r.number(r.member(rho, q, "projection"), q + ".projection");
  }
  return s;
}

// Settings::validate() names the field; map it back to the file's key.
void validate_config(const JsonReader& r, const projection::Settings& s) {
  std::string error;
  if (s.validate(&error)) return;
  std::string key = error.substr(0, error.find_first_of(" ("));
  if (key == "via_step_1") key = "via_steps[0]";
  if (key == "via_step_2") key = "via_steps[1]";
  if (key == "batch") key = "(inputs batch size)";
  if (key == "obstacles") key = "(inputs obstacle count)";
  r.fail("config." + key, error);
}

}  // namespace

ProjectionCase parse_projection_case(const std::string& text, const std::string& source) {
  const JsonReader r(source);
  const json doc = detail::parse_json_text(text, source);
  r.only_keys(doc, "", {"format", "name", "description", "config", "inputs", "expected"});
  const std::string format = r.string(r.member(doc, "", "format"), "format");
  if (format != kProjectionCaseFormat)
    r.fail("format",
           "expected \"" + std::string(kProjectionCaseFormat) + "\", got \"" + detail::printable(format) + "\"");

  ProjectionCase c;
  if (doc.contains("name")) c.name = r.string(doc["name"], "name");
  if (doc.contains("description")) c.description = r.string(doc["description"], "description");
  c.settings = read_settings(r, r.member(doc, "", "config"), "config", true);

  const json& inputs = r.member(doc, "", "inputs");
  r.only_keys(inputs, "inputs",
              {"robot_velocity", "obstacles", "target", "terminal", "via_points", "lambda0", "distance_min",
               "distance_max", "xi_bar"});
  // Sizes come from the inputs themselves: B from robot_velocity, N from the first sample's obstacles.
  int batch = -1;
  c.problem.robot_velocity = read_rows(r, r.member(inputs, "inputs", "robot_velocity"), "inputs.robot_velocity", batch, 2);
  const json& obstacles = r.member(inputs, "inputs", "obstacles");
  if (!obstacles.is_array() || static_cast<int>(obstacles.size()) != batch)
    r.fail("inputs.obstacles", "must be a list of " + std::to_string(batch) + " samples, each a list of [x, y, vx, vy]");
  if (!obstacles[0].is_array()) r.fail("inputs.obstacles[0]", "must be a list of points [x, y, vx, vy]");
  const int N = static_cast<int>(obstacles[0].size());
  c.settings.batch = batch;
  c.settings.obstacles = N;
  validate_config(r, c.settings);
  const int n = c.settings.coefficients(), m = c.settings.steps;

  std::vector<double> points;  // read before sizing the matrix, as in read_rows
  for (int b = 0; b < batch; ++b) {
    const std::string path = at("inputs.obstacles", b);
    if (!obstacles[b].is_array() || static_cast<int>(obstacles[b].size()) != N)
      r.fail(path, "expected " + std::to_string(N) + " points (as in sample 0), got " +
                       (obstacles[b].is_array() ? std::to_string(obstacles[b].size()) : std::string("no list")));
    for (int j = 0; j < N; ++j) {
      const std::vector<double> point = r.numbers(obstacles[b][j], at(path, j), 4);
      points.insert(points.end(), point.begin(), point.end());
    }
  }
  c.problem.obstacles = Eigen::Map<const RowMatrix<double>>(points.data(), batch, 4 * N);
  c.problem.target = read_rows(r, r.member(inputs, "inputs", "target"), "inputs.target", batch, 4);
  c.problem.terminal = read_rows(r, r.member(inputs, "inputs", "terminal"), "inputs.terminal", batch, 4);
  c.problem.via_points = read_rows(r, r.member(inputs, "inputs", "via_points"), "inputs.via_points", batch, 4);
  c.problem.lambda0 = read_rows(r, r.member(inputs, "inputs", "lambda0"), "inputs.lambda0", batch, 2 * n);
  c.problem.distance_min = read_rows(r, r.member(inputs, "inputs", "distance_min"), "inputs.distance_min", batch, m);
  c.problem.distance_max = read_rows(r, r.member(inputs, "inputs", "distance_max"), "inputs.distance_max", batch, m);
  c.problem.xi_bar = read_rows(r, r.member(inputs, "inputs", "xi_bar"), "inputs.xi_bar", batch, 2 * n);

  if (doc.contains("expected")) {
    const json& e = doc["expected"];
    r.only_keys(e, "expected", {"xi_init", "xi", "residual"});
    ProjectionExpected expected;
    expected.xi_init = read_rows(r, r.member(e, "expected", "xi_init"), "expected.xi_init", batch, 2 * n);
    expected.xi = read_rows(r, r.member(e, "expected", "xi"), "expected.xi", batch, 2 * n);
    const std::vector<double> residual = r.numbers(r.member(e, "expected", "residual"), "expected.residual", batch);
    expected.residual = Eigen::Map<const Eigen::VectorXd>(residual.data(), batch);
    c.expected = std::move(expected);
  }
  return c;
}

ProjectionCase read_projection_case(const std::string& path) {
  return parse_projection_case(detail::read_text_file(path), path);
}

namespace {

template <typename M>
json rows_json(const M& matrix) {
  json out = json::array();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    json row = json::array();
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) row.push_back(static_cast<double>(matrix(r, c)));
    out.push_back(std::move(row));
  }
  return out;
}

template <typename V>
json vector_json(const V& v) {
  json out = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(static_cast<double>(v(i)));
  return out;
}

}  // namespace

template <typename T>
std::string projection_result_json(const projection::Result<T>& result, int indent) {
  json out;
  out["xi_init"] = rows_json(result.xi_init);
  out["xi"] = rows_json(result.xi);
  out["residual"] = vector_json(result.residual);
  return out.dump(indent);
}

template std::string projection_result_json<float>(const projection::Result<float>&, int);
template std::string projection_result_json<double>(const projection::Result<double>&, int);

projection::Settings parse_projection_settings(const std::string& json_text, const std::string& source,
                                               const std::string& path, bool strict) {
  const JsonReader r(source);
  return read_settings(r, detail::parse_json_text(json_text, source), path, strict);
}

std::string projection_settings_json(const projection::Settings& s) {
  const json config = {{"degree", s.degree},
                       {"steps", s.steps},
                       {"horizon", s.horizon},
                       {"iterations", s.iterations},
                       {"obstacle_radius", s.obstacle_radius},
                       {"speed_min", s.speed_min},
                       {"speed_max", s.speed_max},
                       {"accel_max", s.accel_max},
                       {"via_steps", {s.via_step_1, s.via_step_2}},
                       {"rho",
                        {{"obstacle", s.rho.obstacle},
                         {"velocity", s.rho.velocity},
                         {"acceleration", s.rho.acceleration},
                         {"tracking", s.rho.tracking},
                         {"projection", s.rho.projection}}}};
  return config.dump();
}

std::string projection_case_json(const ProjectionCase& c, int indent) {
  const auto& s = c.settings;
  json doc;
  doc["format"] = kProjectionCaseFormat;
  doc["name"] = c.name;
  doc["description"] = c.description;
  doc["config"] = json::parse(projection_settings_json(s));
  const auto& p = c.problem;
  json obstacles = json::array();
  for (Eigen::Index b = 0; b < p.obstacles.rows(); ++b) {
    json points = json::array();
    for (int j = 0; j < s.obstacles; ++j)
      points.push_back({p.obstacles(b, 4 * j), p.obstacles(b, 4 * j + 1), p.obstacles(b, 4 * j + 2),
                        p.obstacles(b, 4 * j + 3)});
    obstacles.push_back(std::move(points));
  }
  doc["inputs"] = {{"robot_velocity", rows_json(p.robot_velocity)},
                   {"obstacles", obstacles},
                   {"target", rows_json(p.target)},
                   {"terminal", rows_json(p.terminal)},
                   {"via_points", rows_json(p.via_points)},
                   {"lambda0", rows_json(p.lambda0)},
                   {"distance_min", rows_json(p.distance_min)},
                   {"distance_max", rows_json(p.distance_max)},
                   {"xi_bar", rows_json(p.xi_bar)}};
  if (c.expected) {
    doc["expected"] = {{"xi_init", rows_json(c.expected->xi_init)},
                       {"xi", rows_json(c.expected->xi)},
                       {"residual", vector_json(c.expected->residual)}};
  }
  return doc.dump(indent);
}

}  // namespace occtrack::io
