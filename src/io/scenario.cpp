// Scenario files: reading with every check of shared/spec/simulation.md ("Scenario files"), and writing in
// the spec's layout. Every failure is an InputError "SOURCE: key.path: rule (line N)".
#include "occtrack/io/scenario.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "json_util.hpp"

namespace occtrack::io {

namespace {

using core::Vec2;

constexpr long long kMaxBeams = 1000000;  // a bound that keeps a typo from allocating gigabytes

std::string format_number(double x) {
  if (std::isnan(x)) return ".nan";
  if (std::isinf(x)) return x > 0 ? ".inf" : "-.inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);  // shortest round-trip form
  std::string text(buffer, result.ptr);
  // Keep floats looking like floats ("4.0", not "4"), as in the spec's example.
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

// Four significant digits, for computed values in messages.
std::string short_number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.4g", x);
  return buffer;
}

std::string index_path(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

std::string key_path(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

// A quoted scalar carries the non-specific tag "!": it is a string, never a number.
bool quoted(const YAML::Node& node) { return node.Tag() == "!"; }

std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Undefined: return "nothing";
    case YAML::NodeType::Null: return "null (no value)";
    case YAML::NodeType::Sequence: return "a list of " + std::to_string(node.size());
    case YAML::NodeType::Map: return "a map";
    case YAML::NodeType::Scalar: break;
  }
  std::string text = node.Scalar();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  text = detail::printable(text);
  return quoted(node) ? "the string \"" + text + "\"" : text;
}

// Checked access to the YAML tree, in the manner of detail::JsonReader.
class YamlReader {
 public:
  explicit YamlReader(std::string source) : source_(std::move(source)) {}

  /// Fails with "SOURCE: PATH: RULE (line N)", the line being where `near` starts in the file.
  [[noreturn]] void fail(const std::string& path, const std::string& rule, const YAML::Node& near) const {
    std::string message = source_ + ": " + (path.empty() ? "(top level)" : path) + ": " + rule;
    if (near.IsDefined() && !near.Mark().is_null()) message += " (line " + std::to_string(near.Mark().line + 1) + ")";
    throw InputError(message);
  }

  void require_map(const YAML::Node& node, const std::string& path) const {
    if (!node.IsMap()) fail(path, "must be a map, got " + describe(node), node);
  }

  /// Fails on a key not in `allowed`, a repeated key, or a key that is not a plain name.
  void only_keys(const YAML::Node& node, const std::string& path, std::initializer_list<const char*> allowed) const {
    require_map(node, path);
    std::set<std::string> seen;
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (!it->first.IsScalar()) fail(path, "keys must be names, got " + describe(it->first), it->first);
      const std::string key = it->first.Scalar();
      bool known = false;
      for (const char* name : allowed) known = known || key == name;
      if (!known) {
        std::string list;
        for (const char* name : allowed) list += std::string(list.empty() ? "" : ", ") + name;
        fail(key_path(path, detail::printable(key)), "unknown key (expected one of: " + list + ")", it->first);
      }
      if (!seen.insert(key).second) fail(key_path(path, key), "key given twice", it->first);
    }
  }

  /// Member `key` of the map `node` (at `path`), which must exist.
  YAML::Node member(const YAML::Node& node, const std::string& path, const std::string& key) const {
    require_map(node, path);
    const YAML::Node value = node[key];
    if (!value.IsDefined()) fail(key_path(path, key), "missing required key", node);
    return value;
  }

  /// Member `key` if present, else an undefined node.
  YAML::Node optional(const YAML::Node& node, const std::string& path, const std::string& key) const {
    require_map(node, path);
    return node[key];
  }

  double number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || quoted(node)) fail(path, "must be a number, got " + describe(node), node);
    const std::string& text = node.Scalar();
    std::string lower;
    for (const char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == ".inf" || lower == "+.inf" || lower == "-.inf" || lower == ".nan")
      fail(path, "must be a finite number, got " + text, node);
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (first != last && *first == '+') ++first;
    double x = 0.0;
    const auto [end, error] = std::from_chars(first, last, x);
    if (error == std::errc::result_out_of_range)
      fail(path, "must be a finite number within double range, got " + describe(node), node);
    if (error != std::errc() || end != last || first == last)
      fail(path, "must be a number, got " + describe(node), node);
    if (!std::isfinite(x)) fail(path, "must be a finite number, got " + text, node);
    return x;
  }

  double positive(const YAML::Node& node, const std::string& path) const {
    const double x = number(node, path);
    if (!(x > 0.0)) fail(path, "must be positive, got " + format_number(x), node);
    return x;
  }

  double non_negative(const YAML::Node& node, const std::string& path) const {
    const double x = number(node, path);
    if (x < 0.0) fail(path, "must not be negative, got " + format_number(x), node);
    return x;
  }

  long long integer(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || quoted(node)) fail(path, "must be an integer, got " + describe(node), node);
    const std::string& text = node.Scalar();
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (first != last && *first == '+') ++first;
    long long x = 0;
    const auto [end, error] = std::from_chars(first, last, x);
    const bool huge = error == std::errc() && end == last && std::llabs(x) > 1000000000LL;
    if (error == std::errc::result_out_of_range || huge)
      fail(path, "integer out of range, got " + describe(node), node);
    if (error != std::errc() || end != last || first == last)
      fail(path, "must be an integer, got " + describe(node), node);
    return x;
  }

  std::string string(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) fail(path, "must be a string, got " + describe(node), node);
    return node.Scalar();
  }

  void require_list(const YAML::Node& node, const std::string& path, const std::string& what) const {
    if (!node.IsSequence()) fail(path, "must be a list" + what + ", got " + describe(node), node);
  }

  /// A list of exactly `size` finite numbers; `shape` names them in the message ("[x, y]").
  std::vector<double> numbers(const YAML::Node& node, const std::string& path, std::size_t size,
                              const std::string& shape) const {
    require_list(node, path, " of " + std::to_string(size) + " numbers " + shape);
    if (node.size() != size)
      fail(path, "expected " + std::to_string(size) + " numbers " + shape + ", got " + std::to_string(node.size()),
           node);
    std::vector<double> out;
    out.reserve(size);
    for (std::size_t i = 0; i < size; ++i) out.push_back(number(node[i], index_path(path, i)));
    return out;
  }

  Vec2 point(const YAML::Node& node, const std::string& path) const {
    const std::vector<double> xy = numbers(node, path, 2, "[x, y]");
    return {xy[0], xy[1]};
  }

 private:
  std::string source_;
};

// Signed distance from p to an obstacle at t = 0 (negative inside). io may not use sim (ARCHITECTURE.md), so
// the two formulas of sim::signed_distance are repeated here for the start check.
double start_signed_distance(const core::ObstacleSpec& obstacle, const Vec2& p) {
  const Vec2 offset = p - obstacle.center;
  if (obstacle.shape == core::ObstacleSpec::Shape::circle) return offset.norm() - obstacle.radius;
  const double c = std::cos(obstacle.yaw), s = std::sin(obstacle.yaw);
  const Vec2 local(c * offset.x() + s * offset.y(), -s * offset.x() + c * offset.y());
  const Vec2 q = local.cwiseAbs() - 0.5 * obstacle.size;
  return q.cwiseMax(0.0).norm() + std::min(std::max(q.x(), q.y()), 0.0);
}

core::ObstacleSpec read_obstacle(const YamlReader& r, const YAML::Node& node, const std::string& path) {
  r.require_map(node, path);
  if (node.size() != 1) {
    std::string keys;
    for (auto it = node.begin(); it != node.end(); ++it)
      keys += (keys.empty() ? "" : ", ") +
              (it->first.IsScalar() ? detail::printable(it->first.Scalar()) : describe(it->first));
    r.fail(path, "must be exactly one of `circle:` or `box:`, got " + std::to_string(node.size()) + " keys" +
                     (keys.empty() ? std::string() : " (" + keys + ")"),
           node);
  }
  const auto entry = node.begin();
  const std::string kind = entry->first.IsScalar() ? detail::printable(entry->first.Scalar()) : describe(entry->first);
  const YAML::Node body = entry->second;
  const std::string body_path = path + "." + kind;

  core::ObstacleSpec obstacle;
  if (kind == "circle") {
    r.only_keys(body, body_path, {"center", "radius", "path", "speed"});
    obstacle.shape = core::ObstacleSpec::Shape::circle;
    obstacle.center = r.point(r.member(body, body_path, "center"), body_path + ".center");
    obstacle.radius = r.positive(r.member(body, body_path, "radius"), body_path + ".radius");
  } else if (kind == "box") {
    r.only_keys(body, body_path, {"center", "size", "yaw", "path", "speed"});
    obstacle.shape = core::ObstacleSpec::Shape::box;
    obstacle.center = r.point(r.member(body, body_path, "center"), body_path + ".center");
    const YAML::Node size = r.member(body, body_path, "size");
    r.numbers(size, body_path + ".size", 2, "[x, y]");
    obstacle.size = Vec2(r.positive(size[0], body_path + ".size[0]"), r.positive(size[1], body_path + ".size[1]"));
    if (const YAML::Node yaw = r.optional(body, body_path, "yaw"); yaw.IsDefined())
      obstacle.yaw = r.number(yaw, body_path + ".yaw");
  } else {
    r.fail(body_path, "unknown shape (an obstacle must be exactly one of `circle:` or `box:`)", entry->first);
  }

  // Motion: a path and a speed, both or neither.
  const YAML::Node path_node = r.optional(body, body_path, "path");
  const YAML::Node speed_node = r.optional(body, body_path, "speed");
  if (path_node.IsDefined()) {
    const std::string points_path = body_path + ".path";
    r.require_list(path_node, points_path, " of [x, y] points");
    if (path_node.size() < 2)
      r.fail(points_path, "needs at least 2 points, got " + std::to_string(path_node.size()), path_node);
    for (std::size_t i = 0; i < path_node.size(); ++i)
      obstacle.path.push_back(r.point(path_node[i], index_path(points_path, i)));
    if (!speed_node.IsDefined())
      r.fail(body_path + ".speed", "missing required key (a moving obstacle needs a speed with its path)", body);
    obstacle.speed = r.non_negative(speed_node, body_path + ".speed");
  } else if (speed_node.IsDefined()) {
    r.fail(body_path + ".speed", "given without a path (a speed needs a path to move along)", speed_node);
  }
  return obstacle;
}

core::Scenario read_document(const YamlReader& r, const YAML::Node& root) {
  core::Scenario scenario;
  r.require_map(root, "");
  const YAML::Node format = r.member(root, "", "format");
  if (r.string(format, "format") != kScenarioFormat)
    r.fail("format", std::string("expected ") + kScenarioFormat + ", got " + describe(format), format);
  r.only_keys(root, "", {"format", "name", "duration", "world", "robot", "target", "sensor"});

  const YAML::Node name = r.member(root, "", "name");
  scenario.name = r.string(name, "name");
  if (scenario.name.empty()) r.fail("name", "must not be empty", name);
  scenario.duration = r.positive(r.member(root, "", "duration"), "duration");

  const YAML::Node world = r.member(root, "", "world");
  r.only_keys(world, "world", {"obstacles"});
  const YAML::Node obstacles = r.member(world, "world", "obstacles");
  r.require_list(obstacles, "world.obstacles", " of obstacles (write [] for none)");
  for (std::size_t i = 0; i < obstacles.size(); ++i)
    scenario.obstacles.push_back(read_obstacle(r, obstacles[i], index_path("world.obstacles", i)));

  const YAML::Node robot = r.member(root, "", "robot");
  r.only_keys(robot, "robot", {"position", "velocity", "radius"});
  scenario.robot_position = r.point(r.member(robot, "robot", "position"), "robot.position");
  if (const YAML::Node velocity = r.optional(robot, "robot", "velocity"); velocity.IsDefined())
    scenario.robot_velocity = r.point(velocity, "robot.velocity");
  if (const YAML::Node radius = r.optional(robot, "robot", "radius"); radius.IsDefined())
    scenario.robot_radius = r.positive(radius, "robot.radius");

  const YAML::Node target = r.member(root, "", "target");
  r.only_keys(target, "target", {"radius", "trajectory"});
  if (const YAML::Node radius = r.optional(target, "target", "radius"); radius.IsDefined())
    scenario.target_radius = r.positive(radius, "target.radius");
  const YAML::Node trajectory = r.member(target, "target", "trajectory");
  r.require_list(trajectory, "target.trajectory", " of [t, x, y] waypoints");
  if (trajectory.size() == 0) r.fail("target.trajectory", "needs at least one [t, x, y] waypoint", trajectory);
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const std::string path = index_path("target.trajectory", i);
    const std::vector<double> txy = r.numbers(trajectory[i], path, 3, "[t, x, y]");
    if (i > 0 && !(txy[0] > scenario.target.back().time))
      r.fail(path, "times must be strictly increasing, got t = " + format_number(txy[0]) + " after t = " +
                       format_number(scenario.target.back().time),
             trajectory[i]);
    scenario.target.push_back({txy[0], Vec2(txy[1], txy[2])});
  }

  if (const YAML::Node sensor = r.optional(root, "", "sensor"); sensor.IsDefined()) {
    r.only_keys(sensor, "sensor", {"beams", "range", "noise", "dropout"});
    if (const YAML::Node beams = r.optional(sensor, "sensor", "beams"); beams.IsDefined()) {
      const long long count = r.integer(beams, "sensor.beams");
      if (count < 1) r.fail("sensor.beams", "must be at least 1, got " + std::to_string(count), beams);
      if (count > kMaxBeams)
        r.fail("sensor.beams", "must be at most " + std::to_string(kMaxBeams) + ", got " + std::to_string(count),
               beams);
      scenario.sensor.beams = static_cast<int>(count);
    }
    if (const YAML::Node range = r.optional(sensor, "sensor", "range"); range.IsDefined())
      scenario.sensor.range = r.positive(range, "sensor.range");
    if (const YAML::Node noise = r.optional(sensor, "sensor", "noise"); noise.IsDefined())
      scenario.sensor.noise = r.non_negative(noise, "sensor.noise");
    // Protocol v2: the probability that a beam returns nothing.
    if (const YAML::Node dropout = r.optional(sensor, "sensor", "dropout"); dropout.IsDefined()) {
      scenario.sensor.dropout = r.non_negative(dropout, "sensor.dropout");
      if (scenario.sensor.dropout > 1.0)
        r.fail("sensor.dropout", "must be in [0, 1], got " + format_number(scenario.sensor.dropout), dropout);
    }
  }

  // The robot's disk must start clear of every obstacle (touching is allowed).
  for (std::size_t i = 0; i < scenario.obstacles.size(); ++i) {
    const double distance = start_signed_distance(scenario.obstacles[i], scenario.robot_position);
    if (distance < scenario.robot_radius)
      r.fail("robot.position",
             "the robot's disk (radius " + format_number(scenario.robot_radius) + ") starts inside " +
                 index_path("world.obstacles", i) + " (its centre is " + short_number(distance) +
                 " m from the obstacle's boundary, negative inside)",
             robot["position"]);
  }
  return scenario;
}

// Records where a YAML document starts; ignores its content.
class DocumentStart : public YAML::EventHandler {
 public:
  YAML::Mark mark = YAML::Mark::null_mark();
  void OnDocumentStart(const YAML::Mark& at) override { mark = at; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

// --- Writing.

std::string point_text(const Vec2& p) { return "[" + format_number(p.x()) + ", " + format_number(p.y()) + "]"; }

// A name that YAML reads back unchanged as a plain scalar; anything else is double-quoted and escaped.
std::string name_text(const std::string& name) {
  bool plain = !name.empty() && (std::isalnum(static_cast<unsigned char>(name[0])) || name[0] == '_');
  for (const char c : name)
    plain = plain && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.');
  std::string lower;
  for (const char c : name) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (plain && lower != "null") return name;  // a plain null would read back as no value
  std::string out = "\"";
  for (const char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\x%02x", u);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

core::Scenario parse_scenario(const std::string& yaml_text, const std::string& source) {
  const YamlReader reader(source);
  const auto where = [](const YAML::Mark& mark) {
    return mark.is_null() ? std::string("(top level)")
                          : "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1);
  };
  YAML::Node root;
  try {
    // Count the documents first, at most two parser calls: yaml-cpp 0.7's LoadAll never returns on some bad
    // input (a stray ',' outside any collection yields an empty document forever), and Load would quietly
    // read such input as null or drop every document after the first.
    std::istringstream stream(yaml_text);
    YAML::Parser parser(stream);
    DocumentStart first, second;
    if (!parser.HandleNextDocument(first))
      throw InputError(source + ": (top level): empty file, expected a scenario map");
    if (parser.HandleNextDocument(second)) {
      if (second.mark.pos == first.mark.pos)  // the parser made no progress
        throw InputError(source + ": " + where(second.mark) +
                         ": not valid YAML (unexpected character outside any list or map)");
      throw InputError(source + ": " + where(second.mark) + ": expected one YAML document, found a second one");
    }
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw InputError(source + ": " + where(e.mark) + ": not valid YAML (" + e.msg + ")");
  }
  try {
    return read_document(reader, root);
  } catch (const YAML::Exception& e) {
    // Not expected (the reader checks every node before use); kept so that no yaml-cpp exception escapes.
    const std::string line = e.mark.is_null() ? "" : " (line " + std::to_string(e.mark.line + 1) + ")";
    throw InputError(source + ": (top level): " + e.msg + line);
  }
}

core::Scenario read_scenario(const std::string& path) { return parse_scenario(detail::read_text_file(path), path); }

std::string scenario_yaml(const core::Scenario& s) {
  std::ostringstream out;
  out << "format: " << kScenarioFormat << "\n";
  out << "name: " << name_text(s.name) << "\n";
  out << "duration: " << format_number(s.duration) << "  # simulated seconds\n";
  out << "world:\n";
  if (s.obstacles.empty()) out << "  obstacles: []\n";
  else out << "  obstacles:\n";
  for (const core::ObstacleSpec& o : s.obstacles) {
    if (o.shape == core::ObstacleSpec::Shape::circle)
      out << "    - circle: {center: " << point_text(o.center) << ", radius: " << format_number(o.radius);
    else
      out << "    - box: {center: " << point_text(o.center) << ", size: " << point_text(o.size)
          << ", yaw: " << format_number(o.yaw);
    if (!o.path.empty()) {
      out << ", path: [";
      for (std::size_t i = 0; i < o.path.size(); ++i) out << (i ? ", " : "") << point_text(o.path[i]);
      out << "], speed: " << format_number(o.speed);
    }
    out << "}\n";
  }
  out << "robot: {position: " << point_text(s.robot_position) << ", velocity: " << point_text(s.robot_velocity)
      << ", radius: " << format_number(s.robot_radius) << "}\n";
  out << "target:\n";
  out << "  radius: " << format_number(s.target_radius) << "\n";
  if (s.target.empty()) out << "  trajectory: []\n";
  else out << "  trajectory:  # [t, x, y], linear between waypoints, held after the last\n";
  for (const core::TargetWaypoint& w : s.target)
    out << "    - [" << format_number(w.time) << ", " << format_number(w.position.x()) << ", "
        << format_number(w.position.y()) << "]\n";
  out << "sensor: {beams: " << s.sensor.beams << ", range: " << format_number(s.sensor.range)
      << ", noise: " << format_number(s.sensor.noise);
  if (s.sensor.dropout != 0.0) out << ", dropout: " << format_number(s.sensor.dropout);  // v1 files stay as they were
  out << "}\n";
  return out.str();
}

}  // namespace occtrack::io
