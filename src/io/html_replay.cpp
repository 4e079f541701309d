#include "occtrack/io/html_replay.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "occtrack/io/results.hpp"
#include "occtrack/io/svg.hpp"
#include "occtrack/sim/world.hpp"
#include "document_util.hpp"

namespace occtrack::io {

namespace {

using core::Vec2;
using detail::escape_xml;
using detail::fixed;
using detail::milliseconds;

// ---------------------------------------------------------------------------------------------------------
// The data, written by hand rather than through a json tree: a long episode holds millions of numbers, and
// integer centimetres keep the page small.

class JsonOut {
 public:
  std::string& str() { return out_; }
  JsonOut& raw(const std::string& s) { out_ += s; return *this; }
  JsonOut& raw(const char* s) { out_ += s; return *this; }
  JsonOut& raw(char c) { out_ += c; return *this; }
  JsonOut& key(const char* name) {
    out_ += '"';
    out_ += name;
    out_ += "\":";
    return *this;
  }
  JsonOut& string(const std::string& s) { return raw(nlohmann::json(s).dump()); }

  JsonOut& integer(long long value) {
    char buffer[24];
    const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
    out_.append(buffer, end);
    return *this;
  }
  /// A number in `unit`s (100: centimetres, 1000: milliseconds) rounded to an integer; null when it is not
  /// finite or does not fit.
  JsonOut& scaled(double value, double unit) {
    const double x = std::round(value * unit);
    if (!(std::abs(x) < 1e15)) return raw("null");
    return integer(static_cast<long long>(x));
  }
  JsonOut& cm(double metres) { return scaled(metres, 100.0); }
  /// Seven significant digits (angles); null when not finite.
  JsonOut& real(double value) {
    if (!std::isfinite(value)) return raw("null");
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.7g", value);
    return raw(buffer);
  }
  /// [x0,y0,x1,y1,...] in centimetres.
  JsonOut& points(const std::vector<Vec2>& list) {
    out_ += '[';
    for (std::size_t k = 0; k < list.size(); ++k) {
      if (k > 0) out_ += ',';
      cm(list[k].x()).raw(',').cm(list[k].y());
    }
    out_ += ']';
    return *this;
  }

 private:
  std::string out_;
};

/// At most `max_points` of the path, evenly spaced by index, both ends kept.
std::vector<Vec2> thin(const std::vector<Vec2>& path, int max_points) {
  const std::size_t n = path.size(), m = static_cast<std::size_t>(max_points);
  if (n <= m) return path;
  std::vector<Vec2> out;
  out.reserve(m);
  for (std::size_t k = 0; k < m; ++k) out.push_back(path[(k * (n - 1) + (m - 1) / 2) / (m - 1)]);
  return out;
}

void write_obstacle(JsonOut& j, const core::ObstacleSpec& o) {
  j.raw('{');
  if (o.shape == core::ObstacleSpec::Shape::circle) {
    j.key("kind").raw("\"circle\",").key("r").cm(o.radius);
  } else {
    j.key("kind").raw("\"box\",").key("w").cm(o.size.x()).raw(',').key("h").cm(o.size.y());
    j.raw(',').key("yaw").real(o.yaw);
  }
  j.raw(',').key("x").cm(o.center.x()).raw(',').key("y").cm(o.center.y()).raw('}');
}

/// The moving obstacles' indices, and their centres at every trace time (sim::World's motion, so that the page
/// shows exactly what the episode simulated): [[x, y of each moving obstacle] per frame], flattened.
void write_moving(JsonOut& j, const core::Scenario& scenario, const core::Trace& trace) {
  std::vector<std::size_t> moving;
  for (std::size_t k = 0; k < scenario.obstacles.size(); ++k)
    if (scenario.obstacles[k].moving()) moving.push_back(k);
  j.key("moving").raw('[');
  for (std::size_t k = 0; k < moving.size(); ++k) j.raw(k > 0 ? "," : "").integer(static_cast<long long>(moving[k]));
  j.raw("],").key("moving_xy").raw('[');
  if (!moving.empty()) {
    sim::World world(scenario);
    for (std::size_t i = 0; i < trace.time.size(); ++i) {
      const std::vector<sim::Shape>& shapes = world.shapes_at(trace.time[i]);
      for (std::size_t k = 0; k < moving.size(); ++k) {
        if (i > 0 || k > 0) j.raw(',');
        j.cm(shapes[moving[k]].center.x()).raw(',').cm(shapes[moving[k]].center.y());
      }
    }
  }
  j.raw(']');
}

void write_cycle(JsonOut& j, const core::CycleRecord& c, const HtmlReplayOptions& options) {
  j.raw('{').key("t").scaled(c.time, 1000.0).raw(',').key("robot").points({c.robot}).raw(',');
  // The scan, every step-th beam; -1 for a beam without return (beyond range_max, or not finite): it is the
  // commonest value in open worlds, and two characters where null takes four.
  const core::Scan& scan = c.scan;
  const auto max_beams = static_cast<std::size_t>(options.max_beams);
  const std::size_t step = std::max<std::size_t>(1, (scan.ranges.size() + max_beams - 1) / max_beams);
  j.key("angle_min").real(scan.angle_min).raw(',').key("angle_step").real(scan.angle_increment * step).raw(',');
  j.key("ranges").raw('[');
  for (std::size_t b = 0; b < scan.ranges.size(); b += step) {
    if (b > 0) j.raw(',');
    const double r = scan.ranges[b];
    if (std::isfinite(r) && r <= scan.range_max)
      j.cm(r);
    else
      j.raw("-1");
  }
  j.raw("],").key("plan").points(thin(c.plan, options.max_path_points)).raw(',').key("candidates").raw('[');
  for (std::size_t k = 0; k < c.candidates.size(); ++k) {
    if (k > 0) j.raw(',');
    j.points(thin(c.candidates[k], options.max_path_points));
  }
  j.raw("],").key("command").points({c.command});
  if (*c.safety != '\0') j.raw(',').key("safety").string(c.safety);
  j.raw('}');
}

/// The JSON text fit to sit inside a <script> element: '<' only occurs in strings, where \u003c means the
/// same, so that no "</script>" or "<!--" in a name can end the element early.
std::string script_safe(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (const char c : json) {
    if (c == '<')
      out += "\\u003c";
    else
      out += c;
  }
  return out;
}

std::string replay_data(const core::Scenario& scenario, const core::Trace& trace, const core::EpisodeMetrics& metrics,
                        const std::string& title, const HtmlReplayOptions& options) {
  const SvgFrame frame = episode_svg_frame(scenario, trace);  // the figure's window: everything that moved
  JsonOut j;
  j.str().reserve(4096 + trace.time.size() * 40 + trace.cycles.size() * 3000);
  j.raw('{').key("title").string(title).raw(',');
  j.key("metrics").raw(episode_json(metrics, -1)).raw(',');
  j.key("robot_radius").cm(scenario.robot_radius).raw(',').key("target_radius").cm(scenario.target_radius).raw(',');
  j.key("window").raw('[').cm(frame.x_min).raw(',').cm(frame.y_min).raw(',').cm(frame.x_max).raw(',');
  j.cm(frame.y_max).raw("],");
  j.key("obstacles").raw('[');
  for (std::size_t k = 0; k < scenario.obstacles.size(); ++k) {
    if (k > 0) j.raw(',');
    write_obstacle(j, scenario.obstacles[k]);
  }
  j.raw("],");
  write_moving(j, scenario, trace);
  j.raw(',').key("frames").raw('{').key("t").raw('[');
  for (std::size_t i = 0; i < trace.time.size(); ++i) j.raw(i > 0 ? "," : "").scaled(trace.time[i], 1000.0);
  j.raw("],").key("robot").points(trace.robot).raw(',').key("target").points(trace.target).raw(',');
  j.key("occluded").raw('"');
  for (const char c : trace.occluded) j.raw(c ? '1' : '0');
  j.raw("\"},").key("cycles").raw('[');
  for (std::size_t k = 0; k < trace.cycles.size(); ++k) {
    if (k > 0) j.raw(",\n");
    write_cycle(j, trace.cycles[k], options);
  }
  j.raw("]}");
  return script_safe(j.str());
}

// ---------------------------------------------------------------------------------------------------------
// The page. Colours are io/svg's: obstacles grey, robot blue, target yellow, occluded red, plan green,
// candidates light grey; the scan, which the figure does not show, orange.

constexpr const char* kStyle = R"CSS(<style>
body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;color:#222;margin:12px;background:#fff}
h1{font-size:17px;margin:0 0 8px}
#controls{display:flex;gap:10px;align-items:center;margin-bottom:8px;font-size:13px}
#slider{flex:1;max-width:640px}
#time{font-variant-numeric:tabular-nums;min-width:120px}
#main{display:flex;gap:14px;align-items:flex-start}
canvas{border:1px solid #b4b4b4}
table{border-collapse:collapse;font-size:12.5px}
td,th{padding:2px 8px;border-bottom:1px solid #ebebeb;text-align:left}
td.v{text-align:right;font-variant-numeric:tabular-nums}
.legend{font-size:12px;margin-top:10px;line-height:1.7}
.sw{display:inline-block;width:22px;height:0;border-top:3px solid;vertical-align:middle;margin-right:5px}
.dot{display:inline-block;width:10px;height:10px;border-radius:50%;vertical-align:middle;margin-right:5px}
#selftest{font-size:11px;color:#777}
</style>
)CSS";

constexpr const char* kBody = R"HTML(<div id="controls">
<button id="play" type="button">&#9654; play</button>
<label>speed <select id="speed"><option>0.25</option><option>0.5</option><option selected>1</option>
<option>2</option><option>4</option><option>8</option></select>&times;</label>
<input id="slider" type="range" min="0" max="0" value="0" step="1">
<span id="time"></span>
</div>
<div id="main">
<canvas id="view"></canvas>
<div>
<table id="metrics"><thead><tr><th>metric</th><th>value</th></tr></thead><tbody></tbody></table>
<div class="legend">
<span class="dot" style="background:#9e9e9e"></span>obstacle<br>
<span class="dot" style="background:#1f77b4"></span>robot,
<span class="dot" style="background:#ffc20e"></span>target,
<span class="sw" style="border-top:2px dashed #999"></span>its path<br>
<span class="sw" style="border-color:#1f77b4"></span>line of sight / path, target visible<br>
<span class="sw" style="border-color:#d62728"></span>line of sight / path, target occluded<br>
<span class="dot" style="background:#ff7f0e"></span>LiDAR returns of the cycle<br>
<span class="sw" style="border-color:#2ca02c"></span>chosen plan,
<span class="sw" style="border-color:#c8c8c8"></span>candidates
</div>
</div>
</div>
<pre id="selftest"></pre>
)HTML";

// Script errors are caught from the start, before the replay's own script runs, for the self-test.
constexpr const char* kErrorHook = R"JS(<script>
window.replayErrors = [];
window.addEventListener('error', function (e) {
  window.replayErrors.push(String(e.message) + ' (line ' + e.lineno + ')');
  var out = document.getElementById('selftest');
  if (out && location.hash === '#selftest') out.textContent = 'FAIL script error: ' + window.replayErrors.join('; ');
});
</script>
)JS";

constexpr const char* kScript = R"JS(<script>
'use strict';
(function () {
const D = JSON.parse(document.getElementById('replay-data').textContent);
const C = {bg: '#ffffff', grid: '#ebebeb', obs: '#9e9e9e', obsEdge: '#6e6e6e', robot: '#1f77b4', robotEdge: '#0b3c5d',
           target: '#ffc20e', dark: '#222222', vis: '#1f77b4', occ: '#d62728', plan: '#2ca02c', cand: '#c8c8c8',
           scan: '#ff7f0e'};
const F = D.frames, n = F.t.length, M = D.moving.length;
const canvas = document.getElementById('view'), ctx = canvas.getContext('2d');
const slider = document.getElementById('slider'), playButton = document.getElementById('play');
const speedSelect = document.getElementById('speed'), timeLabel = document.getElementById('time');

// World window (cm) onto the canvas: equal scale on both axes, y up, at most 820 x 760 px.
const [x0, y0, x1, y1] = D.window.map(v => v / 100);
const scale = Math.min(820 / (x1 - x0), 760 / (y1 - y0));
const W = Math.round(scale * (x1 - x0)), H = Math.round(scale * (y1 - y0));
const dpr = window.devicePixelRatio || 1;
canvas.width = Math.round(W * dpr); canvas.height = Math.round(H * dpr);
canvas.style.width = W + 'px'; canvas.style.height = H + 'px';
const px = (x, y) => [(x - x0) * scale, (y1 - y) * scale];
const ok = v => v !== null && v !== undefined;

// Each frame shows the last planning cycle at or before it (-1: none yet).
const cycleOf = new Int32Array(n);
for (let i = 0, c = -1; i < n; ++i) {
  while (c + 1 < D.cycles.length && D.cycles[c + 1].t <= F.t[i]) ++c;
  cycleOf[i] = c;
}

function polyline(flat, colour, width) {  // [x0,y0,x1,y1,...] in cm; a null breaks the line
  ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.lineJoin = ctx.lineCap = 'round';
  ctx.beginPath();
  let pen = false;
  for (let k = 0; k + 1 < flat.length; k += 2) {
    if (!ok(flat[k]) || !ok(flat[k + 1])) { pen = false; continue; }
    const [u, v] = px(flat[k] / 100, flat[k + 1] / 100);
    if (pen) ctx.lineTo(u, v); else ctx.moveTo(u, v);
    pen = true;
  }
  ctx.stroke();
}

function obstacle(o, x, y) {  // x, y: the centre in metres
  ctx.fillStyle = C.obs; ctx.strokeStyle = C.obsEdge; ctx.lineWidth = 1;
  ctx.beginPath();
  if (o.kind === 'circle') {
    const [u, v] = px(x, y);
    ctx.arc(u, v, o.r / 100 * scale, 0, 2 * Math.PI);
  } else {
    const c = Math.cos(o.yaw || 0), s = Math.sin(o.yaw || 0), hw = o.w / 200, hh = o.h / 200;
    [[-1, -1], [1, -1], [1, 1], [-1, 1]].forEach(([a, b], k) => {
      const [u, v] = px(x + a * hw * c - b * hh * s, y + a * hw * s + b * hh * c);
      if (k === 0) ctx.moveTo(u, v); else ctx.lineTo(u, v);
    });
    ctx.closePath();
  }
  ctx.fill(); ctx.stroke();
}

function star(u, v, r) {
  ctx.beginPath();
  for (let k = 0; k < 10; ++k) {
    const a = -Math.PI / 2 + k * Math.PI / 5, q = k % 2 === 0 ? r : 0.45 * r;
    ctx.lineTo(u + q * Math.cos(a), v + q * Math.sin(a));
  }
  ctx.closePath();
  ctx.fillStyle = C.target; ctx.strokeStyle = C.dark; ctx.lineWidth = 1;
  ctx.fill(); ctx.stroke();
}

function grid() {
  ctx.strokeStyle = C.grid; ctx.lineWidth = 1;
  ctx.beginPath();
  for (let x = Math.ceil(x0); x <= x1; ++x) { const u = px(x, 0)[0]; ctx.moveTo(u, 0); ctx.lineTo(u, H); }
  for (let y = Math.ceil(y0); y <= y1; ++y) { const v = px(0, y)[1]; ctx.moveTo(0, v); ctx.lineTo(W, v); }
  ctx.stroke();
}

// The robot's path up to frame i, blue while the target was visible and red while occluded.
function trail(i) {
  let a = 0;
  while (a < i) {
    let b = a;
    while (b < i && F.occluded[b + 1] === F.occluded[a]) ++b;
    polyline(F.robot.slice(2 * a, 2 * Math.min(b + 1, i) + 2), F.occluded[a] === '1' ? C.occ : C.vis, 1.6);
    a = b + 1;
  }
}

let frame = 0;
function draw(i) {
  frame = Math.max(0, Math.min(n - 1, i | 0));
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.fillStyle = C.bg; ctx.fillRect(0, 0, W, H);
  grid();
  // The target's whole path, faint and dashed (the candidates are the light solid lines).
  ctx.globalAlpha = 0.35; ctx.setLineDash([5, 4]); polyline(F.target, C.dark, 1.2);
  ctx.globalAlpha = 1; ctx.setLineDash([]);
  trail(frame);
  const moved = new Map();
  D.moving.forEach((k, m) => moved.set(k, [D.moving_xy[2 * (frame * M + m)], D.moving_xy[2 * (frame * M + m) + 1]]));
  D.obstacles.forEach((o, k) => {
    const [x, y] = moved.has(k) ? moved.get(k) : [o.x, o.y];
    if (ok(x) && ok(y)) obstacle(o, x / 100, y / 100);
  });
  const c = cycleOf[frame] >= 0 ? D.cycles[cycleOf[frame]] : null;
  if (c) {
    c.candidates.forEach(p => polyline(p, C.cand, 0.8));
    polyline(c.plan, C.plan, 2.2);
    if (ok(c.robot[0]) && ok(c.robot[1]) && ok(c.angle_min) && ok(c.angle_step)) {
      ctx.fillStyle = C.scan;
      c.ranges.forEach((r, b) => {
        if (r < 0) return;  // no return
        const a = c.angle_min + b * c.angle_step;
        const [u, v] = px((c.robot[0] + r * Math.cos(a)) / 100, (c.robot[1] + r * Math.sin(a)) / 100);
        ctx.fillRect(u - 1.5, v - 1.5, 3, 3);
      });
    }
  }
  const rx = F.robot[2 * frame], ry = F.robot[2 * frame + 1], tx = F.target[2 * frame], ty = F.target[2 * frame + 1];
  const occluded = F.occluded[frame] === '1';
  if (ok(rx) && ok(ry) && ok(tx) && ok(ty)) {
    ctx.setLineDash(occluded ? [6, 4] : []);
    polyline([rx, ry, tx, ty], occluded ? C.occ : C.vis, 1.5);
    ctx.setLineDash([]);
  }
  if (ok(tx) && ok(ty)) star(...px(tx / 100, ty / 100), Math.max(7, 1.2 * D.target_radius / 100 * scale));
  if (ok(rx) && ok(ry)) {
    const [u, v] = px(rx / 100, ry / 100);
    ctx.beginPath(); ctx.arc(u, v, Math.max(3, D.robot_radius / 100 * scale), 0, 2 * Math.PI);
    ctx.fillStyle = C.robot; ctx.strokeStyle = C.robotEdge; ctx.lineWidth = 1; ctx.fill(); ctx.stroke();
  }
  slider.value = frame;
  // The cycle's command (cm/s) and, with the safety layer, what it did (docs/safety.md, "Fallback").
  const command = c && ok(c.command[0]) && ok(c.command[1])
      ? '  command ' + (Math.hypot(c.command[0], c.command[1]) / 100).toFixed(2) + ' m/s' : '';
  const safety = c && c.safety ? '  safety layer: ' + c.safety : '';
  timeLabel.textContent = 't = ' + (F.t[frame] / 1000).toFixed(2) + ' s' + (occluded ? '  (occluded)' : '') + command + safety;
}

// Metrics: io::episode_json's object, nested keys flattened ("compute_ms.median"), the headline ones first.
function metricsTable() {
  const first = ['scenario', 'planner', 'duration_s', 'occlusion_time_s', 'success', 'collisions', 'min_clearance_m',
                 'compute_ms'].filter(k => k in D.metrics);
  const body = document.querySelector('#metrics tbody');
  const add = (key, value) => {
    if (value !== null && typeof value === 'object') {
      Object.keys(value).forEach(k => add(key + '.' + k, value[k]));
      return;
    }
    const row = body.insertRow();
    row.insertCell().textContent = key;
    const cell = row.insertCell();
    cell.className = 'v';
    cell.textContent = typeof value === 'number' && !Number.isInteger(value) ? value.toFixed(3) : String(value);
  };
  first.concat(Object.keys(D.metrics).filter(k => !first.includes(k))).forEach(k => add(k, D.metrics[k]));
}

// Playback: the slider follows simulated time at the chosen speed.
let playing = false, last = null, simTime = 0;
function advance(seconds) {
  simTime += seconds;
  let i = frame;
  while (i + 1 < n && F.t[i + 1] / 1000 <= simTime) ++i;
  draw(i);
  if (frame === n - 1) setPlaying(false);
}
function tick(now) {
  if (!playing) return;
  if (last !== null) advance((now - last) / 1000 * Number(speedSelect.value));
  last = now;
  requestAnimationFrame(tick);
}
function setPlaying(on) {
  playing = on && n > 1;
  playButton.innerHTML = playing ? '&#10074;&#10074; pause' : '&#9654; play';
  if (playing) {
    if (frame === n - 1) draw(0);
    simTime = F.t[frame] / 1000; last = null;
    requestAnimationFrame(tick);
  }
}
playButton.addEventListener('click', () => setPlaying(!playing));
slider.addEventListener('input', () => { draw(Number(slider.value)); simTime = F.t[frame] / 1000; });
speedSelect.addEventListener('change', () => { last = null; });

document.title = D.title;
slider.max = Math.max(0, n - 1);
metricsTable();
const start = /^#t=([0-9.]+)$/.exec(location.hash);
let first = 0;
if (start) while (first + 1 < n && F.t[first + 1] / 1000 <= Number(start[1])) ++first;
draw(first);

// Self-test (#selftest): slider positions over the episode, each checked for the scene: the robot's and the
// target's colours at their centres (the paths share the robot's blue, so a count would not tell), and
// pixels of the obstacles' and the scan's colours somewhere.
function rgb(hex) { return [1, 3, 5].map(k => parseInt(hex.slice(k, k + 2), 16)); }
function near(p, k, colour) { return colour.every((v, c) => Math.abs(p[k + c] - v) <= 2); }
function pixelIs(x, y, hex) {
  const [u, v] = px(x / 100, y / 100);
  return near(ctx.getImageData(Math.round(u * dpr), Math.round(v * dpr), 1, 1).data, 0, rgb(hex));
}
function count(hex) {
  const p = ctx.getImageData(0, 0, canvas.width, canvas.height).data, colour = rgb(hex);
  let hits = 0;
  for (let k = 0; k < p.length; k += 4) if (near(p, k, colour)) ++hits;
  return hits;
}
function selftest() {
  const failures = [];
  let obstaclePx = 0, scanPx = 0;
  const positions = [0, 0.25, 0.5, 0.75, 1].map(f => Math.round(f * (n - 1)));
  positions.forEach(i => {
    slider.value = i;
    slider.dispatchEvent(new Event('input'));
    if (frame !== i) failures.push('slider ' + i + ' drew frame ' + frame);
    const r = [F.robot[2 * i], F.robot[2 * i + 1]], t = [F.target[2 * i], F.target[2 * i + 1]];
    if (ok(r[0]) && ok(r[1]) && !pixelIs(r[0], r[1], C.robot)) failures.push('no robot at frame ' + i);
    const apart = Math.hypot(r[0] - t[0], r[1] - t[1]) / 100 * scale > Math.max(3, D.robot_radius / 100 * scale) + 2;
    if (ok(t[0]) && ok(t[1]) && apart && !pixelIs(t[0], t[1], C.target)) failures.push('no target at frame ' + i);
    obstaclePx += count(C.obs);
    scanPx += count(C.scan);
  });
  if (D.obstacles.length > 0 && obstaclePx === 0) failures.push('no obstacle drawn');
  if (D.cycles.length > 0 && scanPx === 0) failures.push('no scan drawn');
  if (document.querySelectorAll('#metrics tbody tr').length === 0) failures.push('no metrics');
  draw(0); simTime = 0; advance(1.0);  // playback moves the frame on
  if (n > 1 && frame === 0) failures.push('playback did not advance');
  failures.push(...window.replayErrors);
  document.getElementById('selftest').textContent = (failures.length ? 'FAIL ' + failures.join('; ') : 'ok') +
      ' frames=' + n + ' cycles=' + D.cycles.length + ' positions=' + positions.length +
      ' obstacle_px=' + obstaclePx + ' scan_px=' + scanPx;
}
if (location.hash === '#selftest') {
  try { selftest(); } catch (e) {
    document.getElementById('selftest').textContent = 'FAIL exception: ' + e + ' ' + window.replayErrors.join('; ');
  }
}
})();
</script>
)JS";

void check(const core::Trace& trace, const HtmlReplayOptions& options) {
  std::string error;
  if (!options.validate(&error)) throw std::invalid_argument("episode_html: options: " + error);
  detail::check_trace(trace, "episode_html");
}

/// `text` for an href: unreserved characters and '/' kept, the rest %XX.
std::string url_encode(const std::string& text) {
  static const char* const kHex = "0123456789ABCDEF";
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~' || c == '/') {
      out += ch;
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

std::string page_head(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" + escape_xml(title) +
         "</title>\n";
}

}  // namespace

bool HtmlReplayOptions::validate(std::string* error) const {
  std::ostringstream why;
  if (max_beams < 1)
    why << "max_beams (" << max_beams << ") must be at least 1";
  else if (max_path_points < 2)
    why << "max_path_points (" << max_path_points << ") must be at least 2";
  if (error) *error = why.str();
  return why.str().empty();
}

std::string episode_html(const core::Scenario& scenario, const core::Trace& trace, const core::EpisodeMetrics& metrics,
                         const HtmlReplayOptions& options) {
  check(trace, options);
  const std::string scenario_name = metrics.scenario.empty() ? scenario.name : metrics.scenario;
  const std::string title = options.title.empty() ? scenario_name + " \u2014 " + metrics.planner : options.title;
  std::string page = page_head(title);
  page += kStyle;
  page += kErrorHook;
  page += "</head>\n<body>\n<h1>" + escape_xml(title) + "</h1>\n";
  page += kBody;
  page += "<script type=\"application/json\" id=\"replay-data\">";
  page += replay_data(scenario, trace, metrics, title, options);
  page += "</script>\n";
  page += kScript;
  page += "</body>\n</html>\n";
  return page;
}

std::string suite_html_index(const core::SuiteResult& result, const std::vector<std::string>& pages) {
  if (pages.size() != result.episodes.size())
    throw std::invalid_argument("suite_html_index: " + std::to_string(pages.size()) + " pages for " +
                                std::to_string(result.episodes.size()) + " episodes");
  const std::string title = result.suite + " \u2014 " + result.planner;
  std::string page = page_head(title);
  page += R"(<style>
body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;color:#222;margin:12px}
h1{font-size:17px}
table{border-collapse:collapse;font-size:13px}
td,th{padding:3px 10px;border-bottom:1px solid #ebebeb;text-align:right}
td:first-child,th:first-child{text-align:left}
tr.summary td{font-weight:bold;border-top:2px solid #b4b4b4}
.occ{color:#d62728}
</style>
</head>
<body>
)";
  page += "<h1>" + escape_xml(title) + "</h1>\n<table>\n<tr><th>episode</th><th>occlusion time (s)</th><th>success</th>"
          "<th>collisions</th><th>min clearance (m)</th><th>compute median (ms)</th><th>planner failures</th></tr>\n";
  auto row = [&](const std::string& first_cell, const core::EpisodeMetrics& m, const std::string& success,
                 const char* css_class) {
    page += std::string("<tr") + (css_class ? std::string(" class=\"") + css_class + "\"" : "") + "><td>" + first_cell +
            "</td><td>" + fixed(m.occlusion_time_s, 2) + "</td><td>" + success + "</td><td>" +
            std::to_string(m.collisions) + "</td><td>" + fixed(m.min_clearance_m, 2) + "</td><td>" +
            milliseconds(m.compute_ms.median) + "</td><td>" + std::to_string(m.planner_failures) + "</td></tr>\n";
  };
  for (std::size_t i = 0; i < pages.size(); ++i) {
    const core::EpisodeMetrics& m = result.episodes[i];
    row("<a href=\"" + escape_xml(url_encode(pages[i])) + "\">" + escape_xml(m.scenario) + "</a>", m,
        m.success ? "yes" : "<span class=\"occ\">no</span>", nullptr);
  }
  row("summary (" + std::to_string(pages.size()) + " episodes)", result.summary, fixed(result.success_rate, 2),
      "summary");
  page += "</table>\n</body>\n</html>\n";
  return page;
}

}  // namespace occtrack::io
