import occtrack

# The shipped learned policy tracks a target through a forest for 20 simulated seconds.
result = occtrack.run_episode("scenarios/static-1ms-smoke/forest-a-1.yaml", planner="cvae",
                              latency=20, tau=0.25)
print(f"hidden {result['occlusion_time_s']:.2f} s, {result['collisions']} collisions, "
      f"median cycle {result['compute_ms']['median']:.2f} ms")

# One planning cycle by hand: a robot at the origin, the target 2 m ahead, a wall 3 m to the left.
import numpy as np

ranges = np.full(360, np.inf)
ranges[80:100] = 3.0
planner = occtrack.Planner("cvae", shield=True)
out = planner.plan(robot_position=[0, 0], robot_velocity=[0, 0], target_position=[2, 0],
                   target_velocity=[0.5, 0], ranges=ranges)
print("command", out["command"], "plan", out["plan"].shape, "candidates", out["candidates"].shape)

# A figure of the episode, where matplotlib is installed.
try:
    import matplotlib
    matplotlib.use("Agg")
    ax = occtrack.plot_episode(result, "scenarios/static-1ms-smoke/forest-a-1.yaml")
    ax.figure.savefig("build/forest-a-1.png")
except ImportError:
    pass
