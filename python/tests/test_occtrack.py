"""The Python module against the library: planners, episodes, scenarios, files, and errors that name the
bad argument. Run by ctest (python.pytest) with PYTHONPATH at the build's python/ folder."""
import math
import os
import pathlib

import numpy as np
import pytest

import occtrack

SOURCE = pathlib.Path(os.environ.get("OCCTRACK_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
FOREST = SOURCE / "scenarios" / "static-1ms-smoke" / "forest-a-1.yaml"


def open_scan(beams=360):
    return np.full(beams, np.inf)


def plan_once(planner, **override):
    args = dict(robot_position=[0.0, 0.0], robot_velocity=[0.0, 0.0], target_position=[2.0, 0.0],
                target_velocity=[0.5, 0.0], ranges=open_scan())
    args.update(override)
    return planner.plan(**args)


def test_planner_names_include_the_papers_planners():
    names = occtrack.planner_names()
    for name in ("cvae", "projcem", "follower", "bc"):
        assert name in names


@pytest.mark.parametrize("name", ["follower", "cvae", "projcem"])
def test_cycles_return_finite_commands_that_follow_a_target_in_the_open(name):
    # The target starts 2 m ahead on +x and walks away at 0.5 m/s; the robot, from rest, follows each command
    # within 2 m/s^2 for one second (20 cycles). Every planner closes in. (From rest, a single cycle says little:
    # the shipped cvae's first plans stand, or ease back, for about 0.4 s before it follows.)
    planner = occtrack.Planner(name, shield=False)
    position, velocity, target = np.zeros(2), np.zeros(2), np.array([2.0, 0.0])
    for _ in range(20):
        out = plan_once(planner, robot_position=position, robot_velocity=velocity, target_position=target)
        assert out["ok"], out["message"]
        command = out["command"]
        assert command.shape == (2,) and np.all(np.isfinite(command))
        assert out["plan"].ndim == 2 and out["plan"].shape[1] == 2 and len(out["plan"]) > 1
        assert np.all(np.isfinite(out["plan"]))
        change = command - velocity
        if np.linalg.norm(change) > 0.1:  # 2 m/s^2 over 0.05 s
            change *= 0.1 / np.linalg.norm(change)
        velocity = velocity + change
        position = position + 0.05 * velocity
        target = target + np.array([0.025, 0.0])
    assert command[0] > 0.0, command
    assert position[0] > 0.05, position


def test_the_cvae_returns_its_candidates_as_one_array():
    out = plan_once(occtrack.Planner("cvae", batch=5))
    candidates = out["candidates"]
    assert candidates.ndim == 3 and candidates.shape[2] == 2 and candidates.shape[0] >= 1
    assert out["safety"] in ("plan", "alternative", "stop", "evasive", "best_effort", "brake")
    assert out["beyond_envelope"] is False  # nothing moves in this scan


def test_the_shield_stops_short_of_a_wall_between_robot_and_target():
    # A wall 0.6 m ahead across the whole front half: no plan toward the target can be certified at speed.
    ranges = open_scan()
    angles = np.arange(360) * 2 * math.pi / 360
    front = np.cos(angles) > 0.2
    ranges[front] = 0.6 / np.cos(angles[front])
    out = plan_once(occtrack.Planner("follower", shield=True), robot_velocity=[1.5, 0.0], ranges=ranges)
    assert np.all(np.isfinite(out["command"]))
    assert out["command"][0] < 1.5  # it does not drive on into the wall


@pytest.mark.parametrize("argument,value,message", [
    ("robot_position", [0.0, 0.0, 0.0], "robot_position"),
    ("robot_position", [float("nan"), 0.0], "robot_position"),
    ("target_velocity", [0.0, float("inf")], "target_velocity"),
    ("ranges", np.zeros((4, 4)), "ranges"),
    ("ranges", np.array([]), "ranges"),
    ("ranges", np.array([1.0, float("nan"), 2.0]), "beam 1"),
    ("angle_increment", -0.1, "angle_increment"),
])
def test_a_bad_argument_raises_naming_it(argument, value, message):
    planner = occtrack.Planner("follower")
    with pytest.raises(ValueError, match=message):
        plan_once(planner, **{argument: value})


def test_a_planner_leads_its_command_by_the_latency_too():
    # The command applies 150 ms after the scan: the plan's velocity 0.25 + 0.15 s ahead is the one sent.
    late = plan_once(occtrack.Planner("follower", shield=False, tau=0.25, latency=150))["command"]
    lumped = plan_once(occtrack.Planner("follower", shield=False, tau=0.4))["command"]
    lag_only = plan_once(occtrack.Planner("follower", shield=False, tau=0.25))["command"]
    assert np.array_equal(late, lumped)
    assert np.linalg.norm(late) > np.linalg.norm(lag_only) + 1e-3
    with pytest.raises(ValueError, match="--latency auto"):
        occtrack.Planner("follower", latency="auto")


def test_an_unknown_planner_is_refused_with_the_known_names():
    with pytest.raises(ValueError, match="nope"):
        occtrack.Planner("nope")


def test_settings_are_checked_with_the_command_lines_messages():
    with pytest.raises(ValueError, match="--batch"):
        occtrack.Planner("cvae", batch=0)
    with pytest.raises(TypeError, match="colour"):
        occtrack.Planner("cvae", colour="blue")
    with pytest.raises(ValueError, match="--latency"):
        occtrack.run_episode(FOREST, planner="follower", latency=-3)
    with pytest.raises(ValueError, match="--moving-speed-max"):
        occtrack.Planner("follower", moving_speed_max=0)


def test_run_episode_gives_the_specs_metrics_and_the_trace():
    result = occtrack.run_episode(FOREST, planner="follower", tau=0.25, latency=20)
    for key in ("scenario", "planner", "duration_s", "occlusion_time_s", "collisions", "min_clearance_m",
                "compute_ms", "tracking_distance", "latency_ms"):
        assert key in result
    assert result["duration_s"] == pytest.approx(20.0)
    assert result["latency_ms"] == pytest.approx(20.0)
    trace = result["trace"]
    n = len(trace["time"])
    assert n > 100
    assert trace["robot"].shape == (n, 2) and trace["target"].shape == (n, 2)
    assert trace["occluded"].dtype == bool and trace["occluded"].shape == (n,)
    # The trace and the metrics agree: the time hidden is the hidden samples' share of the episode.
    hidden = trace["occluded"].mean() * result["duration_s"]
    assert hidden == pytest.approx(result["occlusion_time_s"], abs=0.5)


def test_run_episode_matches_the_command_line_bit_for_bit(tmp_path):
    # The same episode twice gives the same metrics (the planners and the simulator are deterministic).
    a = occtrack.run_episode(str(FOREST), planner="cvae", batch=5)
    b = occtrack.run_episode(occtrack.load_scenario(FOREST), planner="cvae", batch=5)
    for key in ("occlusion_time_s", "collisions", "min_clearance_m", "tracking_distance"):
        assert a[key] == b[key]
    np.testing.assert_array_equal(a["trace"]["robot"], b["trace"]["robot"])


def test_scenarios_load_and_generate():
    s = occtrack.load_scenario(FOREST)
    assert s.name and s.duration == pytest.approx(20.0)
    assert s.target.shape[1] == 3 and len(s.obstacles) > 0
    again = occtrack.parse_scenario(s.to_yaml())
    np.testing.assert_allclose(again.target, s.target)
    suite = occtrack.suite_scenarios("static-1ms-smoke")
    assert [x.name for x in suite][:1] == ["forest-a-1"]
    assert suite[0].to_yaml() == s.to_yaml()  # the file in scenarios/ is the generator's
    short = occtrack.suite_scenarios("static-1ms", seed=5000, episodes=1, duration=10)
    assert all(x.duration == pytest.approx(10.0) for x in short)
    with pytest.raises(ValueError, match="unknown suite"):
        occtrack.suite_scenarios("no-such-suite")
    with pytest.raises(ValueError, match="missing.yaml"):
        occtrack.load_scenario("missing.yaml")


def test_scenario_from_a_recorded_path():
    t = np.arange(0.0, 10.0 + 1e-9, 0.01) + 1.7e9  # 100 Hz, a wall clock
    path = np.stack([t, np.full_like(t, 8.0), -5.0 + (t - t[0])], axis=1)  # 1 m/s up x = 8, east of the walls
    s = occtrack.scenario_from_path("six-wall-sliding", path)
    assert s.target.shape == (101, 3) and s.target[0, 0] == 0.0
    np.testing.assert_allclose(s.target[-1], [10.0, 8.0, 5.0], atol=1e-9)
    np.testing.assert_allclose(s.robot_position, [8.0, -7.0])
    assert len(s.obstacles) == 6 and all("path" in o for o in s.obstacles)
    window = occtrack.scenario_from_path(s, path, period=0, from_time=t[100], to_time=t[200], name="window")
    assert window.name == "window" and window.target.shape == (101, 3)
    again = occtrack.parse_scenario(window.to_yaml())
    np.testing.assert_allclose(again.target, window.target)
    through = np.array([[0.0, 0.0, 0.0], [10.0, 10.0, 0.0]])  # straight through the walls
    with pytest.warns(UserWarning, match="overlaps an obstacle"):
        occtrack.scenario_from_path("six-wall", through, robot_start=(-2.0, 0.0))
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        occtrack.scenario_from_path("six-wall", path[:, :2])
    with pytest.raises(ValueError, match="strictly increase"):
        occtrack.scenario_from_path("six-wall", path[::-1])
    # The same path recorded in a frame whose origin is the world's (8, 0) and whose x axis points along +y.
    recorded = np.stack([t, path[:, 2], np.zeros_like(t)], axis=1)
    placed = occtrack.scenario_from_path("six-wall-sliding", recorded, frame=(8.0, 0.0, 90.0))
    np.testing.assert_allclose(placed.target, s.target, atol=1e-9)
    with pytest.warns(UserWarning, match="overlaps an obstacle"):
        occtrack.scenario_from_path("six-wall-sliding", recorded)  # read in the world's frame: through walls
    with pytest.raises(ValueError, match=r"angle \(400.000000 degrees\) must be within \[-360, 360\]"):
        occtrack.scenario_from_path("six-wall", path, frame=(0.0, 0.0, 400.0))
    with pytest.raises(ValueError, match="offset"):
        occtrack.scenario_from_path("six-wall", path, frame=(2e6, 0.0, 0.0))


def test_models_load_as_arrays():
    tensors, metadata = occtrack.load_model(str(SOURCE / "models" / "cvae.safetensors"))
    assert metadata["format"].startswith("occtrack.model")
    assert len(tensors) > 4
    assert all(isinstance(a, np.ndarray) and np.all(np.isfinite(a)) for a in tensors.values())
    with pytest.raises(ValueError):
        occtrack.load_dataset(str(SOURCE / "models" / "cvae.safetensors"))  # a model is not a dataset


def test_datasets_load_as_arrays():
    columns, metadata = occtrack.load_dataset(str(SOURCE / "tests" / "data" / "datasets" / "v1-sim.safetensors"))
    assert metadata["format"] == "occtrack.dataset.v1"
    rows = columns["observation"].shape[0]
    assert rows > 0 and columns["observation"].shape == (rows, 6)
    assert columns["expert_xi"].shape[0] == rows and columns["episode"].dtype in (np.int32, np.int64)


def test_the_readme_shows_the_example_as_it_is():
    example = (SOURCE / "python" / "examples" / "track.py").read_text()
    readme = (SOURCE / "README.md").read_text()
    assert "```python\n" + example + "```" in readme


def test_run_episode_writes_the_replay_page(tmp_path):
    page = tmp_path / "forest.html"
    occtrack.run_episode(FOREST, planner="follower", html=page)
    text = page.read_text()
    assert 'id="replay-data"' in text and "https://" not in text
    with pytest.raises(ValueError, match="cannot write"):
        occtrack.run_episode(FOREST, planner="follower", html=tmp_path / "no-such-folder" / "x.html")


def test_scan_angles_as_an_array():
    planner = occtrack.Planner("follower")
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False)
    a = plan_once(planner, angles=angles)
    planner.reset()
    b = plan_once(planner, angle_min=-math.pi, angle_increment=2 * math.pi / 360)
    np.testing.assert_array_equal(a["command"], b["command"])
    with pytest.raises(ValueError, match="angles"):
        plan_once(planner, angles=angles[:10])
    uneven = angles.copy()
    uneven[5] += 0.01
    with pytest.raises(ValueError, match="evenly spaced"):
        plan_once(planner, angles=uneven)
