"""Write the chapter notebooks from their cell sources (run: python tools/make_notebooks.py).

Keeping the sources here makes notebook diffs reviewable; the .ipynb files are committed without
outputs and executed by nbval (tests) and Jupyter Book (the book).
"""

from __future__ import annotations

from pathlib import Path

import nbformat as nbf

ROOT = Path(__file__).resolve().parents[1] / "notebooks"


def md(text: str):
    return nbf.v4.new_markdown_cell(text.strip())


def code(text: str):
    return nbf.v4.new_code_cell(text.strip())


CH1 = [
    md("""
# 1. The world, the robot and its camera

**Learning objectives.** After this chapter you can

- describe the obstacle course of the paper (Section 3.1) and how our simulator reproduces it;
- explain the onboard depth camera: what a pixel's value means and why the field of view matters;
- draw the 25 motion primitives and play them back on the robot;
- run an episode of the Gymnasium environment `HuskyNav-v0`.

The paper's robot is a Clearpath Husky in PyBullet, driving through a 10 × 10 m course with 20
cylinders whose height is 100 × `robot_height` = 7.5 m. The paper samples positions and radii
uniformly but never prints the ranges, so we calibrated them (chapter 2) to reproduce its one
hard number: the random policy survives 4.4 primitives per video.
"""),
    code("""
import numpy as np
import matplotlib.pyplot as plt
import gymnasium as gym

import husky_course
from husky_course.config import get_profile
from husky_course.artifacts import get_dataset
from husky_course.backends import make_simulator
from husky_course import plotting, widgets

profile = get_profile()  # HUSKY_PROFILE=quick (default) or full
cfg = profile.sim
print("profile:", profile.name)
"""),
    md("""
## The course (the paper's Figure 2, with a map)

Left: what an ordinary camera on the robot would see. Middle: the depth image the network gets,
in the perceptually uniform *viridis* colormap like the paper's Figure 2 (dark = close, yellow =
nothing within 5 m). Right: the course from above, the robot's collision disc in blue, side walls
in grey (they stop the robot from driving around the course), the finish line dashed.

In a live notebook the slider below the figure changes the world seed; in the book you see the
figure at its default value.
"""),
    code("""
widgets.world_explorer(default_seed=0)
"""),
    md("""
## Every world comes from one seed

A world is pure data, generated from an integer seed by a numpy `Generator`: the same seed gives
the same course on any machine. The start pose is drawn first; any obstacle that would touch the
robot's start disc is redrawn, so the robot never starts in collision.
"""),
    code("""
# NBVAL_CHECK_OUTPUT
from husky_course.world import make_world
w = make_world(0, cfg.world)
print("obstacles:", w.obstacles.shape, " height (m):", cfg.world.obstacle_height)
print("first obstacle (x, y, r):", np.round(w.obstacles[0], 3))
print("start pose (x, y, yaw):", np.round(w.start, 3))
print("same seed, same world:", np.array_equal(make_world(0, cfg.world).obstacles, w.obstacles))
"""),
    md("""
## The camera model

The camera is fixed to the chassis (not on a joint, where PyBullet's renderer can hang),
`mount_forward` ahead of the base centre and `mount_height` above the ground, looking straight
ahead. A pixel holds the depth *along the view axis* `z` (not the distance along the ray).
PyBullet returns an OpenGL depth-buffer value `d`; we linearise it with
`z = far·near / (far − (far − near)·d)` and normalise to `(z − near)/(far − near)` in [0, 1].
"""),
    code("""
# NBVAL_CHECK_OUTPUT
cam = cfg.camera
print(f"image {cam.size}x{cam.size}, field of view {cam.fov_deg:.0f} deg, near {cam.near} m, far {cam.far} m")
print(f"mounted {cam.mount_forward} m ahead of the base centre, {cam.mount_height} m above the ground")
print(f"robot collision cylinder radius {cfg.world.robot_radius} m")
"""),
    md("""
### Choosing the field of view

The paper does not give one. A planner that sees only the current image cannot avoid an obstacle
it cannot see, so we measured, over robot poses from the dataset, which fraction of the obstacles
that a primitive *would hit* is visible in the image, for several fields of view.
"""),
    code("""
ds = get_dataset()
from husky_course.fov import hit_visibility
rng = np.random.default_rng(0)
sample = rng.choice(len(ds), size=min(len(ds), 600), replace=False)
fovs = [60, 90, 110, 130, 150]
vis = hit_visibility(ds.world_seeds[ds.episode[sample]], ds.poses[sample], fovs, cfg)
fig, ax = plt.subplots(figsize=(5, 3))
ax.bar([str(f) for f in fovs], [100 * vis[f] for f in fovs],
       color=["tab:blue" if f == cam.fov_deg else "0.6" for f in fovs])  # ours in blue
ax.set_xlabel("field of view (deg)"); ax.set_ylabel("hit obstacles in view (%)")
plt.show()
print(f"With 90 deg the robot sees {vis[90]:.0%} of what its next primitive could hit; "
      f"with our {cam.fov_deg:.0f} deg (the lab's own choice) it sees {vis[cam.fov_deg]:.0%}.")
"""),
    md("""
The rest are obstacles beside the camera or hidden behind nearer ones. Wider than 130° the
perspective image stretches badly at its edges, so 130° is our compromise.

## The 25 motion primitives

The paper uses *record and playback*: each primitive is a smooth forward manoeuvre that ends at
the heading it started from. Ours are S-curves that advance 1 m along the course (ten primitives
cross it) and shift the robot sideways by one of 25 evenly spaced offsets. Each is recorded as
101 poses and played back *kinematically* (`resetBasePositionAndOrientation`), as the lab's code
does: the real Husky's skid-steer would slip.
"""),
    code("""
sim = make_simulator("fast", cfg)
lib = sim.library
fig, ax = plt.subplots(figsize=(5, 4))
plotting.draw_library(lib, cfg.world.robot_radius, ax)
ax.set_title("the primitive library (dotted: the robot's swept width)", fontsize=9)
plt.show()
"""),
    code("""
# NBVAL_CHECK_OUTPUT
lengths = lib.path_lengths()
print(f"{lib.n} primitives; lateral offsets {lib.offsets[0]:+.2f} ... {lib.offsets[-1]:+.2f} m")
print(f"path lengths {lengths.min():.3f} ... {lengths.max():.3f} m; all end at heading 0:",
      bool(np.allclose(lib.local_paths[:, -1, 2], 0)))
"""),
    md("""
A primitive collides if the robot's collision cylinder touches an obstacle or a wall at any of
its recorded poses; the poses are at most 2.6 cm apart, far less than the smallest obstacle.

## An episode in the Gymnasium environment

`gym.make("HuskyNav-v0")` gives the standard interface: the action is a primitive index, the
observation the depth image, `terminated` means collision and `truncated` means the course was
crossed (10 primitives).
"""),
    code("""
env = gym.make("HuskyNav-v0", backend="fast")
obs, info = env.reset(seed=0)
rng = np.random.default_rng(1)
frames, done = [obs], False
while not done:
    obs, reward, terminated, truncated, info = env.step(int(rng.integers(25)))
    frames.append(obs)
    done = terminated or truncated
base = env.unwrapped
fig, ax = plt.subplots(figsize=(8, 4))
plotting.draw_world(base.sim.world, ax, info["pose"])
for path in base.path:
    plotting.draw_path(path, ax)
plt.show()
fig, axes = plt.subplots(1, len(frames), figsize=(1.6 * len(frames), 1.9))
for t, (axi, f) in enumerate(zip(np.atleast_1d(axes), frames)):
    plotting.show_depth(f, axi, f"t={t}")
plt.show()
print(f"{info['step']} primitives applied, collision: {info['collision']}")
env.close()
"""),
    md("""
## Exercises

1. Change `default_seed` in the explorer. Find a world where the start is boxed in: which
   primitives could still be safe?
2. The depth along the view axis differs from the distance along the ray. For a pixel in the
   image's corner (130° field of view), by what factor? *(Hint: the ray direction is
   `(1, u, v)`; check with `husky_course.camera.pixel_tangents`.)*
3. Re-run the field-of-view measurement with `fovs = [90, 130]` and a robot radius of 0.3 m
   (`dataclasses.replace`). Does the gap between the two grow or shrink? Why?
"""),
]

CH2 = [
    md("""
# 2. Collecting data with a random policy

**Learning objectives.** After this chapter you can

- explain how the paper's dataset is made (Section 3.2): videos of at most 10 primitives, chosen
  at random, ending at the first collision;
- read the single-indexed pool and its `-1` convention, and avoid its off-by-one trap;
- build the two training sets the paper uses (encoder/decoder pairs and the reward set);
- trust the fast simulator because it was checked against PyBullet.
"""),
    code("""
import json
import tempfile

import numpy as np
import matplotlib.pyplot as plt

from husky_course.config import get_profile
from husky_course.artifacts import get_dataset, dataset_dir
from husky_course.collect import collect
from husky_course.dataset import load_dataset, stats, encoder_decoder_pairs, reward_set
from husky_course.backends import make_simulator
from husky_course import plotting

profile = get_profile()
ds = get_dataset(profile)  # built once (with a progress bar) and reused
print("dataset:", dataset_dir(profile).name, "| profile:", profile.name)
"""),
    md("""
## The random policy and one tiny, reproducible collection

Video `v` of a collection with seed `s` drives in world `s·10⁶ + v` and draws its primitives from
`default_rng([s, v])`, uniformly over the 25. A video therefore depends on `(s, v)` only: the
dataset is byte-identical for any number of worker processes, and a killed collection resumes
from its finished shards. The same command is available on the command line:
`python -m husky_course collect --profile full --workers 2 --out DIR`.
"""),
    code("""
# NBVAL_CHECK_OUTPUT
with tempfile.TemporaryDirectory() as tmp:
    small = collect(tmp + "/demo", profile, videos=50, seed=0, progress=False)
    print(json.dumps(stats(load_dataset(small)), indent=1))
"""),
    md("""
## How long do random videos last?

We count every primitive applied in a video, **the colliding one included** (it is the step
whose image carries safety label 1). The paper reports 4.4 on average.
"""),
    code("""
s = stats(ds)
fig, ax = plt.subplots(figsize=(6, 3))
ax.hist(ds.lengths, bins=np.arange(0.5, 11.5), rwidth=0.85, color="tab:blue")
ax.axvline(s["mean_primitives_per_video"], color="k", label=f"ours: {s['mean_primitives_per_video']:.2f}")
ax.axvline(4.4, color="tab:red", ls="--", label="paper: 4.4")
ax.set_xlabel("primitives per video"); ax.set_ylabel("videos"); ax.legend()
plt.show()
print(f"{s['videos']} videos, {s['images']} images; mean {s['mean_primitives_per_video']:.2f} primitives per video; "
      f"{s['videos_surviving']} videos ({s['videos_surviving'] / s['videos']:.1%}) crossed the course.")
"""),
    md("""
The calibration that gives this mean (full profile: 10,000 videos) is in `husky_course/config.py`:
obstacle radii uniform in [0.15, 0.35] m, obstacles only beyond the first 2 m (a start zone),
start `y` uniform in [−2, 2] m, primitives advancing 1 m with lateral offsets up to ±0.8 m, and a
robot collision cylinder of radius 0.45 m.

## The single-indexed pool and the −1 convention

All images of all videos are appended into one array. The paper marks where a video ends in a
collision by writing `-1` into the primitive array at that step; the safety label is 1 exactly
there. We keep the primitive that was really applied in a separate array `applied`, and the
video index of every image in `episode`, so nothing is ambiguous. A video that survives all 10
primitives ends after its 10th image with no `-1` at all.
"""),
    code("""
# two consecutive videos, the first ending in a collision
v = int(np.flatnonzero(ds.collided[:-1])[0])
idx = np.concatenate([ds.video(v), ds.video(v + 1)])
print("pool index :", " ".join(f"{i:4d}" for i in idx))
print("episode    :", " ".join(f"{e:4d}" for e in ds.episode[idx]))
print("prims      :", " ".join(f"{p:4d}" for p in ds.prims[idx]))
print("applied    :", " ".join(f"{p:4d}" for p in ds.applied[idx]))
print("label      :", " ".join(f"{l:4d}" for l in ds.labels[idx]))
"""),
    md("""
**The trap.** The encoder/decoder learns *image t + primitive t → image t+1*. Pairing pool entry
`i` with `i+1` is only right when step `i` was safe *and* `i+1` belongs to the same video. The
paper's filter (drop label-1 images) handles collisions, but the last image of a video that
survived all 10 primitives would be paired with the first image of the next video. We filter on
the episode index too.
"""),
    code("""
fig, axes = plt.subplots(3, 10, figsize=(15, 5))
for row, v in enumerate(np.flatnonzero(ds.lengths >= 4)[:3]):
    idx = ds.video(v)
    for t in range(10):
        ax = axes[row, t]
        if t < len(idx):
            lab = "COLLIDES" if ds.labels[idx[t]] else f"prim {ds.applied[idx[t]]}"
            plotting.show_depth(ds.image(idx[t]), ax, f"t={t}: {lab}")
        else:
            ax.set_axis_off()
fig.suptitle("depth sequences of three videos up to the collision", fontsize=10)
plt.show()
"""),
    md("""
## The two training sets of the paper
"""),
    code("""
pairs = encoder_decoder_pairs(ds, seed=0)
rs = reward_set(ds, seed=0)
n_unsafe = int(ds.labels[np.concatenate([rs.train, rs.val])].sum())
n_safe = len(rs.train) + len(rs.val) - n_unsafe
print(f"encoder/decoder pairs: {len(pairs.train_t)} train / {len(pairs.val_t)} validation (80/20)")
print(f"reward set: all {n_unsafe} unsafe + 50% of safe = {n_safe} safe images; "
      f"safe:unsafe = {n_safe / n_unsafe:.2f}:1 (paper: 1.7:1); "
      f"{len(rs.train)} train / {len(rs.val)} validation")
for name, split in [("train", rs.train), ("validation", rs.val)]:
    print(f"  {name}: {ds.labels[split].mean():.1%} unsafe")
"""),
    md("""
## Fast simulator vs PyBullet

PyBullet's renderer makes about 80–160 images per second here; the paper's 44,000 images would
take minutes. Everything in the course is vertical and the camera never tilts, so the first
surface a pixel's ray meets depends only on its column: our `fast` backend ray-casts analytically
in numpy, batched over many poses. It reproduces the renderer's conventions: pixels sampled at
integer raster positions with rows flipped. Both backends draw each cylinder as the same
20-sided prism: the outline PyBullet itself builds for a cylinder, handed to its renderer as an
explicit mesh. (PyBullet's own cylinder visual adds a 1 mm margin and an outline that changes
with height, enough to move a silhouette that grazes a pixel's sample point by one column.)
`tests/test_fast_vs_pybullet.py` requires a 99th-percentile error of at most 0.02 on every one of
250 views, and identical collision labels on 1,000+ primitive applications; here are a few.
"""),
    code("""
fast, ref = make_simulator("fast", profile.sim), make_simulator("pybullet", profile.sim)
rows = np.flatnonzero(ds.step == 2)[:4]
fig, axes = plt.subplots(3, len(rows), figsize=(2.6 * len(rows), 7.5))
errs = []
for c, i in enumerate(rows):
    seed, pose = int(ds.world_seeds[ds.episode[i]]), ds.poses[i].astype(float)
    fast.load(seed); ref.load(seed)
    a, b = fast.depth(pose[None])[0], ref.depth(pose[None])[0]
    errs.append(np.percentile(np.abs(a - b), 99))
    plotting.show_depth(a, axes[0, c], "fast")
    plotting.show_depth(b, axes[1, c], "PyBullet")
    axes[2, c].imshow(a - b, cmap="RdBu", vmin=-0.2, vmax=0.2); axes[2, c].set_axis_off()
    axes[2, c].set_title("difference", fontsize=9)
plt.show()
ref.close()
print("99th percentile of |fast - PyBullet| per image:", ", ".join(f"{e:.1e}" for e in errs))
"""),
    md("""
## Exercises

1. Collect 200 videos with `backend="pybullet"` and the same seed as a fast collection. Are the
   safety labels identical? How much longer did it take?
2. Write the naive pairing `(i, i+1) for every i with label 0` and count how many of its pairs
   cross from one video to the next. What would the decoder learn from them?
3. The reward set keeps half of the safe images. What ratio would you get by keeping all of them,
   and how would a classifier that always answers "safe" score on each?
"""),
]


def keep_checked_outputs(nb) -> None:
    """Drop every output except those of ``# NBVAL_CHECK_OUTPUT`` cells (which nbval compares).

    Checked cells keep their execution count: nbval treats a cell without one as never run.
    """
    nb.metadata.pop("widgets", None)
    for i, cell in enumerate(nb.cells):
        cell.id = f"cell-{i:02d}"  # stable ids: regenerating a chapter changes only what changed
        cell.metadata.pop("execution", None)  # timestamps: they would make every regeneration a diff
        if cell.cell_type == "code" and "NBVAL_CHECK_OUTPUT" not in cell.source:
            cell.outputs = []
            cell.execution_count = None


def main() -> None:
    """Write each chapter (or those named on the command line), execute it once in the quick
    profile and keep only the checked outputs."""
    import os

    from nbclient import NotebookClient

    os.environ["HUSKY_PROFILE"] = "quick"
    os.environ.pop("MPLBACKEND", None)  # the inline backend must draw the figures
    os.environ["HUSKY_STATIC_WIDGETS"] = "1"  # no live widget state stored in the committed files
    ROOT.mkdir(exist_ok=True)
    import sys

    from chapters import ch03, ch04, ch05, ch06, ch07

    chapters = {
        "01_environment": CH1,
        "02_data_collection": CH2,
        "03_encoder_decoder": ch03.CELLS,
        "04_reward_net_failure": ch04.CELLS,
        "05_joint_training": ch05.CELLS,
        "06_rnn_lookahead": ch06.CELLS,
        "07_planner_evaluation": ch07.CELLS,
    }
    wanted = sys.argv[1:] or list(chapters)
    unknown = [w for w in wanted if w not in chapters]
    if unknown:
        raise SystemExit(f"unknown chapter(s) {unknown}; choose from {list(chapters)}")
    for name in wanted:
        cells = chapters[name]
        print("executing", name, flush=True)
        nb = nbf.v4.new_notebook()
        nb.cells = cells
        nb.metadata["kernelspec"] = {
            "name": "python3",
            "display_name": "Python 3",
            "language": "python",
        }
        NotebookClient(
            nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}
        ).execute()
        keep_checked_outputs(nb)
        nbf.write(nb, ROOT / f"{name}.ipynb")


if __name__ == "__main__":
    main()
