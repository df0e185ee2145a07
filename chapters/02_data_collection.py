# %% [markdown]
# # 2. Collecting data with a random policy
#
# **Learning objectives.** After this chapter you can
#
# - explain how the paper's dataset is made (Section 3.2): videos of at most 10 primitives, chosen
#   at random, ending at the first collision;
# - read the single-indexed pool and its `-1` convention, and avoid its off-by-one trap;
# - build the two training sets the paper uses (encoder/decoder pairs and the reward set);
# - trust the fast simulator because it was checked against PyBullet.

# %%
import json
import tempfile
import time

import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Markdown, display

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.course.policies import POLICIES, policy_lengths, policy_videos
from husky_course.data.calibration import best_range, calibrate, mean_interval
from husky_course.data.collect import collect
from husky_course.data.dataset import load_dataset, stats
from husky_course.data.splits import encoder_decoder_pairs, reward_set
from husky_course.data.store import dataset_dir, get_dataset
from husky_course.sim.backends import make_simulator
from husky_course.sim.world import obstacle_outline
from husky_course.ui import plotting
from husky_course.ui.plotting import markdown_table

profile = get_profile()
ds = get_dataset(profile)  # built once (with a progress bar) and reused
print("dataset:", dataset_dir(profile).name, "| profile:", profile.name)

# %% [markdown]
# ## The random policy and one tiny, reproducible collection
#
# Video `v` of a collection with seed `s` drives in world `s·10⁶ + v` and draws its primitives from
# `default_rng([s, v])`, uniformly over the 25. A video therefore depends on `(s, v)` only: the
# dataset is byte-identical for any number of worker processes, and a killed collection resumes
# from its finished shards. The same command is available on the command line:
# `python -m husky_course collect --profile full --workers 2 --out DIR`.

# %%
# NBVAL_CHECK_OUTPUT
with tempfile.TemporaryDirectory() as tmp:
    small = collect(tmp + "/demo", profile, videos=50, seed=0, progress=False)
    print(json.dumps(stats(load_dataset(small)), indent=1))

# %% [markdown]
# ## How long do random videos last?
#
# We count every primitive applied in a video, **the colliding one included** (it is the step
# whose image carries safety label 1). The paper reports 4.4 on average.

# %%
s = stats(ds)
fig, ax = plt.subplots(figsize=(6, 3))
ax.hist(ds.lengths, bins=np.arange(0.5, profile.sim.max_primitives + 1.5), rwidth=0.85, color="tab:blue")
ax.axvline(s["mean_primitives_per_video"], color="k", label=f"ours: {s['mean_primitives_per_video']:.2f}")
ax.axvline(profile.calibration.target, color="tab:red", ls="--",
           label=f"paper: {profile.calibration.target}")
ax.set_xlabel("primitives per video")
ax.set_ylabel("videos")
ax.legend()
plt.show()
survived = s["videos_surviving"]
print(f"{s['videos']} videos, {s['images']} images; mean {s['mean_primitives_per_video']:.2f} primitives "
      f"per video; {survived} videos ({survived / s['videos']:.1%}) crossed the course.")

# %% [markdown]
# ## The calibration behind that mean
#
# The paper fixes the course and the random policy but not the obstacles' radii; its one hard
# number is the mean video length. So we swept the radius range: for each candidate, random-policy
# videos in worlds of a collection seed *other than the dataset's* (the worlds we tuned on are not
# the worlds we report), their mean length and a 95% interval. Only lengths are needed, so no image
# is rendered and the sweep takes seconds. The other choices of the course are printed below it.

# %%
rows = calibrate(profile.sim, profile.calibration, progress=False)
display(Markdown(markdown_table([r.row() for r in rows])))
best = best_range(rows, profile.calibration.target)
chosen = tuple(profile.sim.world.radius_range)
print(f"nearest to the paper's {profile.calibration.target}: radii {best.radius_range} "
      f"(mean {best.mean:.2f}, 95% interval [{best.lo:.2f}, {best.hi:.2f}], "
      f"{'holds' if best.lo <= profile.calibration.target <= best.hi else 'misses'} the target); "
      f"the configured range {chosen} is {'this one' if best.radius_range == chosen else 'another one'}.")
w, prim = profile.sim.world, profile.sim.primitives
print(f"also fixed in the config: obstacles only beyond x = {w.obstacle_x_min} m (a start zone), "
      f"start y uniform in ±{w.start_half_width} m, primitives advancing {prim.advance} m with lateral "
      f"offsets up to ±{prim.lateral_spread} m, a robot collision cylinder of radius {w.robot_radius} m.")

# %% [markdown]
# ## Two readings of "a policy with random weights"
#
# The paper's videos come from "a policy with random weights (used to randomly determine which
# primitive to apply at each step)", in its introduction "a policy based on the PAC-Bayes framework
# that uses a set of random weights". Our dataset reads this as **uniform**: each primitive drawn
# independently and uniformly, whatever the image shows. The words allow a second reading, the
# **random network**: a network with freshly drawn weights looks at each depth image and applies the
# primitive it scores highest, as the lab's PAC-Bayes planners draw a policy's weights and then act
# on the image. For it we take the paper's encoder (image → 15 numbers) and one fully connected
# layer to 25 scores, initialised by PyTorch's default rule, one fresh network per video (seeded by
# the video; the head is our choice, since none of the paper's networks outputs a primitive).
#
# Both readings drive in the same worlds, those of the dataset's first videos, and we count
# primitives as above (the colliding one included, at most the paper's 10). Since a world is shared,
# the difference between the two readings is also measured world by world (a paired interval).

# %%
n_pol = policy_videos(profile)
played = {name: policy_lengths(profile.sim, name, n_pol, profile.data.seed) for name in POLICIES}
summary, single, table = {}, {}, []
for name, (lengths, prims) in played.items():
    summary[name] = mean_interval(lengths)
    single[name] = np.mean([len(np.unique(p)) == 1 for p in prims if len(p) >= 2])  # one manoeuvre repeated
    table.append({"reading": name, "videos": n_pol, "mean primitives per video": f"{summary[name][0]:.2f}",
                  "95% interval": f"[{summary[name][1]:.2f}, {summary[name][2]:.2f}]",
                  "videos of 2+ primitives repeating one primitive": f"{single[name]:.0%}"})
display(Markdown(markdown_table(table)))
fig, ax = plt.subplots(figsize=(6, 3))
bins = np.arange(0.5, profile.sim.max_primitives + 1.5)
for k, (name, (lengths, _)) in enumerate(played.items()):
    ax.hist(lengths, bins=bins + 0.2 * k - 0.1, rwidth=0.4, label=name)
ax.set_xlabel("primitives per video")
ax.set_ylabel("videos")
ax.legend()
plt.show()
uniform_lengths, network_lengths = played["uniform"][0], played["random network"][0]
if len(ds.lengths) >= n_pol:
    print("the uniform reading replays the dataset's first videos exactly:",
          bool(np.array_equal(uniform_lengths, ds.lengths[:n_pol])))

# %%
(mu_u, lo_u, hi_u), (mu_n, lo_n, hi_n) = summary["uniform"], summary["random network"]
d, d_lo, d_hi = mean_interval(network_lengths - uniform_lengths)
target = profile.calibration.target
inside = {name: lo <= target <= hi for name, (_, lo, hi) in summary.items()}
overlap = lo_u <= hi_n and lo_n <= hi_u
print(f"uniform: {mu_u:.2f} [{lo_u:.2f}, {hi_u:.2f}]; random network: {mu_n:.2f} [{lo_n:.2f}, {hi_n:.2f}] "
      f"primitives per video over {n_pol} videos each; the two intervals "
      f"{'overlap' if overlap else 'do not overlap'}.")
print(f"world by world, random network minus uniform: {d:+.2f} [{d_lo:+.2f}, {d_hi:+.2f}]: "
      + ("the two readings give different video lengths on these worlds." if d_lo > 0 or d_hi < 0 else
         "these videos cannot tell the two readings apart by their length."))
print(f"the paper's {target} lies "
      + " and ".join(f"{'inside' if inside[n] else 'outside'} the {n} reading's interval" for n in POLICIES)
      + (": its one number does not decide between them." if all(inside.values()) else "."))

# %%
print(f"Length is not all that differs: of the videos of at least 2 primitives, {single['random network']:.0%} "
      f"apply one and the same primitive at every step under the random network, {single['uniform']:.0%} under "
      "the uniform policy"
      + ("; a freshly initialised network's highest score often stays on the same primitive from one image "
         "to the next, so its videos show the decoder fewer different primitives per world."
         if single["random network"] > single["uniform"] else "."))

# %% [markdown]
# The course keeps the uniform reading: the paper's parenthesis ("used to randomly determine which
# primitive to apply at each step") describes it most directly, and the obstacle radii were calibrated
# on it.

# %% [markdown]
# ## The single-indexed pool and the −1 convention
#
# All images of all videos are appended into one array. The paper marks where a video ends in a
# collision by writing `-1` into the primitive array at that step; the safety label is 1 exactly
# there. We keep the primitive that was really applied in a separate array `applied`, and the
# video index of every image in `episode`, so nothing is ambiguous. A video that survives all its
# primitives (the paper's 10) ends after its last image with no `-1` at all.

# %%
# two consecutive videos, the first ending in a collision
v = int(np.flatnonzero(ds.collided[:-1])[0])
idx = np.concatenate([ds.video(v), ds.video(v + 1)])
print("pool index :", " ".join(f"{i:4d}" for i in idx))
print("episode    :", " ".join(f"{e:4d}" for e in ds.episode[idx]))
print("prims      :", " ".join(f"{p:4d}" for p in ds.prims[idx]))
print("applied    :", " ".join(f"{p:4d}" for p in ds.applied[idx]))
print("label      :", " ".join(f"{lab:4d}" for lab in ds.labels[idx]))

# %% [markdown]
# **The trap.** The encoder/decoder learns *image t + primitive t → image t+1*. Pairing pool entry
# `i` with `i+1` is only right when step `i` was safe *and* `i+1` belongs to the same video. The
# paper's filter (drop label-1 images) handles collisions, but the last image of a video that
# survived all its primitives would be paired with the first image of the next video. We filter on
# the episode index too.

# %%
steps = profile.sim.max_primitives
fig, axes = plt.subplots(3, steps, figsize=(1.5 * steps, 5))
for row, v in enumerate(np.flatnonzero(ds.lengths >= 4)[:3]):
    idx = ds.video(v)
    for t in range(steps):
        ax = axes[row, t]
        if t < len(idx):
            lab = "COLLIDES" if ds.labels[idx[t]] else f"prim {ds.applied[idx[t]]}"
            plotting.show_depth(ds.image(idx[t]), ax, f"t={t}: {lab}")
        else:
            ax.set_axis_off()
fig.suptitle("depth sequences of three videos up to the collision", fontsize=10)
plt.show()

# %% [markdown]
# ## The two training sets of the paper

# %%
data = profile.data
pairs = encoder_decoder_pairs(ds, seed=data.seed, val_fraction=data.val_fraction)
rs = reward_set(ds, seed=data.seed, safe_fraction=data.reward_safe_fraction, val_fraction=data.val_fraction)
n_unsafe = int(ds.labels[np.concatenate([rs.train, rs.val])].sum())
n_safe = len(rs.train) + len(rs.val) - n_unsafe
print(f"videos held out for validation: {data.val_fraction:.0%}")
print(f"encoder/decoder pairs: {len(pairs.train_t)} train / {len(pairs.val_t)} validation")
print(f"reward set: all {n_unsafe} unsafe + {data.reward_safe_fraction:.0%} of safe = {n_safe} safe images; "
      f"safe:unsafe = {n_safe / n_unsafe:.2f}:1 (paper: 1.7:1); "
      f"{len(rs.train)} train / {len(rs.val)} validation")
for name, split in [("train", rs.train), ("validation", rs.val)]:
    print(f"  {name}: {ds.labels[split].mean():.1%} unsafe")

# %% [markdown]
# ## Fast simulator vs PyBullet
#
# PyBullet's renderer is slow at this: the cell below measures its rate, and what it means for the
# paper's 44,000 images. Everything in the course is vertical and the camera never tilts, so the
# first surface a pixel's ray meets depends only on its column: our `fast` backend ray-casts
# analytically in numpy, batched over many poses. It reproduces the renderer's conventions: pixels
# sampled at integer raster positions with rows flipped. Both backends draw each cylinder as the
# same prism (its number of sides is printed below): the outline PyBullet itself builds for a
# cylinder, handed to its renderer as an explicit mesh. (PyBullet's own cylinder visual adds a 1 mm
# margin and an outline that changes with height, enough to move a silhouette that grazes a pixel's
# sample point by one column.)
# `tests/test_fast_vs_pybullet.py` bounds the largest per-pixel difference on every one of many
# random views, and requires identical collision labels on many random primitive applications;
# here are a few views, with both backends timed.

# %%
fast, ref = make_simulator("fast", profile.sim), make_simulator("pybullet", profile.sim)
rows = np.flatnonzero(ds.step == 2)[:4]
fig, axes = plt.subplots(3, len(rows), figsize=(2.6 * len(rows), 7.5))
errs, t_fast, t_ref = [], 0.0, 0.0
for c, i in enumerate(rows):
    seed, pose = int(ds.world_seeds[ds.episode[i]]), ds.poses[i].astype(float)
    fast.load(seed)
    ref.load(seed)
    t0 = time.perf_counter()
    a = fast.depth(pose[None])[0]
    t1 = time.perf_counter()
    b = ref.depth(pose[None])[0]
    t_fast, t_ref = t_fast + t1 - t0, t_ref + time.perf_counter() - t1
    errs.append(np.abs(a - b).max())
    plotting.show_depth(a, axes[0, c], "fast")
    plotting.show_depth(b, axes[1, c], "PyBullet")
    axes[2, c].imshow(a - b, cmap="RdBu", vmin=-0.2, vmax=0.2)
    axes[2, c].set_axis_off()
    axes[2, c].set_title("difference", fontsize=9)
plt.show()
ref.close()
print(f"obstacle prism: {len(obstacle_outline())} sides")
print("largest |fast - PyBullet| per image:", ", ".join(f"{e:.1e}" for e in errs))
print(f"one image: PyBullet {1e3 * t_ref / len(rows):.1f} ms ({len(rows) / t_ref:.0f} images/s), "
      f"fast backend {1e3 * t_fast / len(rows):.2f} ms (one pose at a time; batches are faster still)")
print(f"at these rates the paper's 44,000 images take {44_000 * t_ref / len(rows) / 60:.1f} min "
      f"with PyBullet, {44_000 * t_fast / len(rows):.1f} s with the fast backend")

# %% [markdown]
# ## Exercises
#
# 1. Collect 200 videos with `backend="pybullet"` and the same seed as a fast collection. Are the
#    safety labels identical? How much longer did it take?
# 2. Write the naive pairing `(i, i+1) for every i with label 0` (and `i+1` still in the pool) and
#    count how many of its pairs cross from one video to the next. Check your count with
#    `exercises.check_naive_pairs(ds, your_count)`. What would the decoder learn from them?
# 3. The reward set keeps half of the safe images. What ratio would you get by keeping all of them,
#    and how would a classifier that always answers "safe" score on each?
