# %% [markdown]
# # 1. The world, the robot and its camera
#
# **Learning objectives.** After this chapter you can
#
# - describe the obstacle course of the paper (Section 3.1) and how our simulator reproduces it;
# - explain the onboard depth camera: what a pixel's value means and why the field of view matters;
# - draw the 25 motion primitives and play them back on the robot;
# - run an episode of the Gymnasium environment `HuskyNav-v0`.
#
# The paper's robot is a Clearpath Husky in PyBullet, driving through a 10 × 10 m course with 20
# cylinders whose height is 100 × `robot_height` (our value is printed below). The paper samples
# positions and radii uniformly but never prints the ranges, so we calibrated them (chapter 2) to
# reproduce its one hard number: the random policy survives 4.4 primitives per video.

# %%
import gymnasium as gym
import matplotlib.pyplot as plt
import numpy as np

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.data.store import get_dataset
from husky_course.sim.backends import make_simulator
from husky_course.ui import plotting, widgets

profile = get_profile()  # HUSKY_PROFILE=quick (default) or full
cfg = profile.sim
print("profile:", profile.name)

# %% [markdown]
# ## The course (the paper's Figure 2, with a map)
#
# Left: what an ordinary camera on the robot would see. Middle: the depth image the network gets,
# in the perceptually uniform *viridis* colormap like the paper's Figure 2 (dark = close, yellow =
# nothing within the far plane, printed below). Right: the course from above, the robot's collision disc in blue, side walls
# in grey (they stop the robot from driving around the course), the finish line dashed.
#
# In a live notebook a slider above the figure changes the world seed and the figure redraws in
# place; in the book (no kernel) a player steps through the first few worlds instead.

# %%
widgets.world_explorer(default_seed=0)

# %% [markdown]
# ## Every world comes from one seed
#
# A world is pure data, generated from an integer seed by a numpy `Generator`: the same seed gives
# the same course on any machine. The start pose is drawn first; any obstacle that would touch the
# robot's start disc is redrawn, so the robot never starts in collision.

# %%
# NBVAL_CHECK_OUTPUT
from husky_course.sim.world import make_world

w = make_world(0, cfg.world)
print("obstacles:", w.obstacles.shape, " height (m):", cfg.world.obstacle_height)
print("first obstacle (x, y, r):", np.round(w.obstacles[0], 3))
print("start pose (x, y, yaw):", np.round(w.start, 3))
print("same seed, same world:", np.array_equal(make_world(0, cfg.world).obstacles, w.obstacles))

# %% [markdown]
# ## The camera model
#
# The camera is fixed to the chassis (not on a joint, where PyBullet's renderer can hang),
# `mount_forward` ahead of the base centre and `mount_height` above the ground, looking straight
# ahead. A pixel holds the depth *along the view axis* `z` (not the distance along the ray).
# PyBullet returns an OpenGL depth-buffer value `d`; we linearise it with
# `z = far·near / (far − (far − near)·d)` and normalise to `(z − near)/(far − near)` in [0, 1].

# %%
# NBVAL_CHECK_OUTPUT
cam = cfg.camera
print(f"image {cam.size}x{cam.size}, field of view {cam.fov_deg:.0f} deg, near {cam.near} m, far {cam.far} m")
print(f"mounted {cam.mount_forward} m ahead of the base centre, {cam.mount_height} m above the ground")
print(f"robot collision cylinder radius {cfg.world.robot_radius} m")

# %% [markdown]
# ### Choosing the field of view
#
# The paper does not give one. A planner that sees only the current image cannot avoid an obstacle
# it cannot see, so we measured, over robot poses from the dataset, which fraction of the obstacles
# that a primitive *would hit* is visible in the image, for several fields of view.

# %%
ds = get_dataset(profile)
from husky_course.course.fov import hit_visibility

rng = np.random.default_rng(0)
sample = rng.choice(len(ds), size=min(len(ds), 600), replace=False)
fovs = [60, 90, 110, 130, 150]
vis = hit_visibility(ds.world_seeds[ds.episode[sample]], ds.poses[sample], fovs, cfg)
fig, ax = plt.subplots(figsize=(5, 3))
ax.bar([str(f) for f in fovs], [100 * vis[f] for f in fovs],
       color=["tab:blue" if f == cam.fov_deg else "0.6" for f in fovs])  # ours in blue
ax.set_xlabel("field of view (deg)")
ax.set_ylabel("hit obstacles in view (%)")
plt.show()
print(f"With 90 deg the robot sees {vis[90]:.0%} of what its next primitive could hit; "
      f"with the configured {cam.fov_deg:.0f} deg it sees {vis[cam.fov_deg]:.0%}.")

# %% [markdown]
# The rest are beside the camera, hidden behind nearer obstacles or beyond the far plane. Since the
# paper gives no field of view, the configured one (printed above) is our choice, and a compromise:
# a narrower one misses more of what the next primitive could hit, and a much wider one stretches
# the perspective image badly at its edges.
#
# ## The 25 motion primitives
#
# The paper uses *record and playback*: each primitive is a smooth forward manoeuvre that ends at
# the heading it started from. Ours are S-curves that advance a fixed distance along the course and
# shift the robot sideways by one of 25 evenly spaced offsets (the sizes are printed below). Each is
# recorded as a dense sequence of poses and played back *kinematically*
# (`resetBasePositionAndOrientation`), as the lab's code does: the real Husky's skid-steer would slip.

# %%
sim = make_simulator("fast", cfg)
lib = sim.library
fig, ax = plt.subplots(figsize=(5, 4))
plotting.draw_library(lib, cfg.world.robot_radius, ax)
ax.set_title("the primitive library (dotted: the robot's swept width)", fontsize=9)
plt.show()

# %%
# NBVAL_CHECK_OUTPUT
lengths = lib.path_lengths()
print(f"{lib.n} primitives; lateral offsets {lib.offsets[0]:+.2f} ... {lib.offsets[-1]:+.2f} m")
print(f"path lengths {lengths.min():.3f} ... {lengths.max():.3f} m; all end at heading 0:",
      bool(np.allclose(lib.local_paths[:, -1, 2], 0)))

# %% [markdown]
# A primitive collides if the robot's collision cylinder touches an obstacle or a wall at any of
# its recorded poses; the cell below measures how far apart those poses are, against the smallest
# obstacle.

# %%
prim = cfg.primitives
gap = np.linalg.norm(np.diff(lib.local_paths[..., :2], axis=1), axis=-1).max()
print(f"each primitive advances {prim.advance} m ({cfg.max_primitives} of them cross the course) "
      f"and is recorded as {prim.samples} poses, at most {100 * gap:.1f} cm apart; the smallest obstacle "
      f"radius is {cfg.world.radius_range[0]} m; the camera sees {cam.fov_deg:.0f} deg wide, "
      f"up to {cam.far} m.")

# %% [markdown]
# ## An episode in the Gymnasium environment
#
# `gym.make("HuskyNav-v0")` gives the standard interface: the action is a primitive index, the
# observation the depth image, `terminated` means collision and `truncated` means the course was
# crossed (after `cfg.max_primitives` primitives, printed above; the paper's videos have 10).

# %%
env = gym.make("HuskyNav-v0", backend="fast")
obs, info = env.reset(seed=0)
rng = np.random.default_rng(1)
frames, done = [obs], False
while not done:
    obs, reward, terminated, truncated, info = env.step(int(rng.integers(env.action_space.n)))
    frames.append(obs)
    done = terminated or truncated
base = env.unwrapped
fig, ax = plt.subplots(figsize=(8, 4))
plotting.draw_world(base.sim.world, ax, info["pose"])
for path in base.path:
    plotting.draw_path(path, ax)
plt.show()
fig, axes = plt.subplots(1, len(frames), figsize=(1.6 * len(frames), 1.9))
for t, (axi, f) in enumerate(zip(np.atleast_1d(axes), frames, strict=True)):
    plotting.show_depth(f, axi, f"t={t}")
plt.show()
print(f"{info['step']} primitives applied, collision: {info['collision']}")
env.close()

# %% [markdown]
# ## Exercises
#
# 1. Change `default_seed` in the explorer. Find a world where the start is boxed in: which
#    primitives could still be safe?
# 2. The depth along the view axis differs from the distance along the ray. For the pixel in the
#    image's corner (the one farthest from its centre, at the configured field of view), by what
#    factor is the distance along its ray larger than its depth? *(Hint: the ray direction is
#    `(1, u, v)`, with `u, v` from `husky_course.sim.camera.pixel_tangents(cfg.camera)`.)* Check
#    with `exercises.check_ray_factor(cfg.camera, your_factor)`.
# 3. Re-run the field-of-view measurement with `fovs = [90, 130]` and a robot radius of 0.3 m
#    (`dataclasses.replace`). Does the gap between the two grow or shrink? Why?
