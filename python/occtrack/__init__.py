"""occtrack: occlusion-aware target tracking from Python.

The planners, the simulator, scenario files, datasets and models of the C++ library (the extension module
``occtrack._occtrack``); settings are the command line's options as keyword arguments (``latency=20`` is
``--latency 20``, ``shield=False`` is ``--no-shield``) and are checked with the same messages.

    import occtrack
    result = occtrack.run_episode("scenarios/static-1ms-smoke/forest-a-1.yaml", planner="cvae")
    print(result["occlusion_time_s"], result["collisions"])
"""

from ._occtrack import (  # noqa: F401  (the public API)
    InputError,
    Planner,
    Scenario,
    load_dataset,
    load_model,
    load_scenario,
    load_tensors,
    parse_scenario,
    planner_names,
    run_episode,
    scenario_from_path,
    suite_names,
    suite_scenarios,
)


def plot_episode(result, scenario=None, ax=None):
    """Draws an episode's trace (run_episode's result) with matplotlib: the obstacles at t = 0 when the
    scenario is given, the target's path, and the robot's path red where the target was hidden. Returns the
    axes. Raises ImportError when matplotlib is not installed (Debian: python3-matplotlib)."""
    import matplotlib.patches as patches
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    if scenario is not None:
        if not isinstance(scenario, Scenario):
            scenario = load_scenario(scenario)
        for o in scenario.obstacles:
            if o["shape"] == "circle":
                ax.add_patch(patches.Circle(o["center"], o["radius"], color="0.6"))
            else:
                w, h = o["size"]
                corner = o["center"] - [w / 2, h / 2]
                ax.add_patch(patches.Rectangle(corner, w, h, angle=o["yaw"] * 57.29577951308232,
                                               rotation_point="center", color="0.6"))
    trace = result["trace"]
    ax.plot(trace["target"][:, 0], trace["target"][:, 1], color="tab:green", label="target")
    ax.plot(trace["robot"][:, 0], trace["robot"][:, 1], color="tab:blue", label="robot")
    hidden = trace["robot"][trace["occluded"]]
    if len(hidden):
        ax.scatter(hidden[:, 0], hidden[:, 1], s=4, color="tab:red", label="target hidden", zorder=3)
    ax.set_aspect("equal")
    ax.set_title(f"{result['scenario']} ({result['planner']}): hidden {result['occlusion_time_s']:.1f} s, "
                 f"{result['collisions']} collisions")
    ax.legend(loc="best")
    return ax
