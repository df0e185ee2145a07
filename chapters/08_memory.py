# %% [markdown]
# # 8. Memory: what the robot saw before
#
# **Learning objectives.** After this chapter you can
#
# - measure what limits a planner that sees only the current image, with perfect perception as a
#   thought experiment;
# - build an obstacle map from depth images and the robot's own motion (dead reckoning), and plan
#   over it with the oracle's exact lattice search;
# - train a learned planner with memory from a privileged teacher on the states it reaches itself
#   (DAgger), and judge it against the classical mapping planner;
# - find what limits a planner by climbing a ladder of references on the tuning set, and build the
#   learned model plus exact search that the ladder points to;
# - state a collision certificate after choosing the best of several planners, honestly.
#
# Chapter 7 ended by splitting the best learned planner's collisions into those with an obstacle the
# current image showed and those with one it did not: only memory can avoid the second kind. The paper's introduction contrasts learning with
# *mapping*, the classical approach that remembers the world; this chapter builds both and compares
# them on the same held-out worlds.
#
# **Who may know what.** Every planner here, learned or not, receives the depth images, the
# primitives it applied and its own primitive library, nothing else (the oracle is the one
# *privileged* planner; `tests/test_privileged.py` checks this). The two "perfect perception"
# planners below are privileged analysis tools, never candidates.

# %%
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import HTML, Markdown, display

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.course.ladder import static_ladder
from husky_course.evaluation.analysis import collision_cause
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.evaluation.stored import evaluate_stored
from husky_course.imitation.dagger import get_memory
from husky_course.imitation.discs import get_discs
from husky_course.planners.reference import SeenObstaclesPlanner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.ui import animation, plotting
from husky_course.ui.plotting import markdown_table

profile = get_profile()
N, REPORT = profile.eval.worlds, profile.eval.seed  # the reporting set: nothing is tuned on it
N_TUNE, TUNE = profile.eval.tuning_worlds, profile.eval.tuning_seed  # the tuning set: every choice is made here
W = profile.eval.workers  # worlds are evaluated in W processes; every number but the timings is the same for any W
sim = FastSimulator(profile.sim)
print(f"profile {profile.name}: {N} held-out worlds of evaluation set {REPORT}")

# %% [markdown]
# ## References: perfect perception, with and without memory
#
# Two thought experiments. Both replan at every step with the oracle's exact search and the true
# geometry, but only over the obstacles they have *seen*: the first over those the current image
# renders (an obstacle counts when it is the nearest surface of at least one image column within the
# far plane: field of view, occlusion and thin obstacles between columns included), the second over
# every obstacle any image so far has rendered. Nothing learned, nothing mispredicted: the only
# difference is memory. They are references, not ceilings: both treat space no image has shown as
# free, and a planner that learns what such space tends to hold (for example, to keep away from it)
# could do better than either without seeing more.

# %%
references = {
    name: evaluate_stored(p, N, REPORT, profile, progress=False, workers=W) for name, p in [
        ("seen now (perfect perception)", SeenObstaclesPlanner(memory=False)),
        ("seen so far (perfect perception)", SeenObstaclesPlanner(memory=True)),
        ("oracle (every obstacle)", make_planner("oracle"))]
}
display(Markdown(markdown_table([
    {"planner": k, "success": r.success_rate,
     "95% interval": f"[{r.success_ci95[0]:.3f}, {r.success_ci95[1]:.3f}]"}
    for k, r in references.items()])))
now, ever, oracle = (r.success_rate for r in references.values())
display(Markdown(
    f"With perfect perception of the current image alone, {now:.1%} of the worlds are crossed; remembering "
    f"every obstacle seen so far raises it to {ever:.1%}, {ever / oracle:.0%} of the oracle's {oracle:.1%}. "
    + ("Between these references, memory buys more than what separates perfect perception of the seen "
       "from the oracle." if ever - now > oracle - ever else
       "Here memory buys less than what separates perfect perception of the seen from the oracle.")))

# %% [markdown]
# ## A map from images and dead reckoning (no learning)
#
# The mapping planner turns each depth image into a laser scan (one point per column that sees a
# vertical surface, with an uncertainty radius of half the gap between columns), keeps every point
# in the robot's own frame, and after each primitive moves the map by the primitive's known
# displacement. Where the camera looks now, the current image overrides the memory; beside and
# behind the robot, memory is all there is. It then plans with the oracle's lattice search over the
# map (unknown space counts as free; it replans after every image). Its horizon and safety margin
# were chosen on evaluation set 1, the tuning set (see `husky_course/planners/mapping.py`).
#
# The player below steps through one held-out episode of the memory student (next section): the
# black dots are its map, drawn where they lie in the world; on the right, the map as the student
# reads it. It works in the built book without a kernel.

# %%
# NBVAL_CHECK_OUTPUT
from husky_course.planners.perception import DepthScan, EgoMap

first = sim.load(int(eval_world_seeds(1, REPORT)[0]))
ego = EgoMap(DepthScan(profile.sim), forget_behind=profile.memory.map_behind)
ego.add(sim.depth(first.start[None])[0])
print("points the first image adds to the map:", len(ego.points))
EXAMPLE = profile.course.example_primitive
end = sim.library.local_paths[EXAMPLE, -1]
before = ego.points[:, :2].copy()
ego.move(float(end[0]), float(end[1]))
kept = before[before[:, 0] - end[0] > -profile.memory.map_behind]
print(f"after primitive {EXAMPLE} every point moved by", np.round(-end[:2], 3).tolist(), "exactly:",
      bool(np.allclose(ego.points[:, :2], kept - end[:2])))

# %%
student = get_memory(profile)  # trained by `python -m husky_course train memory` (part of `train all`)
memory_planner = make_planner("memory", profile=profile)
episode, frames = animation.record_map_episode(memory_planner, sim, int(eval_world_seeds(N, REPORT)[3]))
display(HTML(animation.map_player(sim, episode, frames)))

# %% [markdown]
# ## The memory student: the oracle as a privileged teacher (DAgger)
#
# The student's network reads two things: the current depth image through the paper's encoder
# (chapter 3), and the map above as a small top-down image through two convolutions. It predicts,
# for every primitive, how many of the next steps the best continuation starting with it survives:
# the simulator's labels, computed with the oracle's search in the true world. Memory lives in the
# map, not in a recurrent state: an obstacle beside the robot is a point in the map whether or not
# the camera still sees it, and reading it costs the network one forward pass (its time per decision
# is in the results table below).
#
# Training follows DAgger: round 0 drives with the teacher's actions (the student only watches and
# builds its map), later rounds drive with the student's own choices, so the data contains the
# states the student actually reaches, its mistakes included; every state is labelled by the
# teacher and the network is retrained on everything so far. Training worlds come from a seed range
# no evaluation uses.

# %%
display(Markdown(markdown_table([
    {"round": r["round"], "who drives": r["acting"], "states added": r["states"],
     "success in its training worlds": r["success_in_its_worlds"]} for r in student.rounds] or
    [{"round": "-", "who drives": "-", "states added": "-", "success in its training worlds": "-"}])))

# %% [markdown]
# ## What the map loses: a ladder on the tuning set
#
# The mapping planner and the perfect-perception planner above search the same way over the same
# seen world; they differ only in what they search over. The ladder below changes one thing per
# rung, on the tuning set (never the reporting set): the mapping planner's raw scan points (each
# fattened by half the gap between neighbouring columns, 0.2 m at the far plane); the same with no
# safety margin; a map of *discs*, one per cylinder the camera glimpsed, read by a network (next
# section) or, as a privileged reference, from the truth; every seen cylinder exactly; the oracle.
# The references are not ceilings: each is optimistic about space no image has shown.

# %%
discs_model, discs_history, _ = get_discs(profile)  # trained by `python -m husky_course train discs`
ladder = {name: evaluate_stored(p, N_TUNE, TUNE, profile, progress=False, workers=W)
          for name, p in static_ladder(profile)}
display(Markdown(markdown_table([
    {"rung (tuning set)": k, "success": r.success_rate,
     "95% interval": f"[{r.success_ci95[0]:.3f}, {r.success_ci95[1]:.3f}]"} for k, r in ladder.items()])))
gain = ladder["discs"].success_rate - ladder["mapping"].success_rate
truth_gap = ladder["discs, read from the truth"].success_rate - ladder["discs"].success_rate
display(Markdown(
    f"On {N_TUNE} tuning worlds, reading the map as discs changes the success rate by {gain:+.1%} against the "
    f"mapping planner; a perfect reader of the same pieces would change it by a further {truth_gap:+.1%}. "
    "(The full-profile ladder on 1,000 tuning worlds: `python benchmarks/exp_static_ladder.py`.)"))

# %% [markdown]
# ## A learned model of what the camera glimpsed, searched exactly
#
# The disc planner (`husky_course/planners/discs.py`) is the paper's structure, a learned model
# plus a search, with the model learning what the ladder says is missing. Each depth image's scan is
# cut into pieces of surface (the tracker's cut, chapter 10); a small network reads each piece (16
# of its points in a frame that looks from the camera at it, its range and width, whether the image
# edge or a nearer surface cuts it) and says whether it belongs to a cylinder and, if so, where the
# cylinder's centre is and how large it is. The map keeps those discs, moves them by dead reckoning
# and drops one the camera sees through; walls, and the points of a piece that its disc does not
# explain, stay scan points. The mapping planner's exact search plans over that map. The network
# is trained on pieces of random views in training worlds, labelled by the simulator with the
# cylinder each column hit (`husky_course/imitation/discs.py`); its margin and the tolerance for
# unexplained points were chosen on the tuning set (`DiscConfig`). A cylinder standing beside another,
# or partly behind it, often stays joined to it in one piece, and one disc then covers only one of the
# two: a second small network (`husky_course/planners/cuts.py`) reads every boundary between two
# neighbouring points of a piece, with the disc network's read of the parts either side, and the piece
# is cut again where it says two cylinders meet. It learns from the same views, labelled where the
# columns' cylinder changes (`husky_course/imitation/cuts.py`). The disc planner uses it on the moving
# course (chapter 10), where a neighbour lost from the map costs most; here it is left out (its module
# gives the measurements).
#
# Below, one image of a reporting world read both ways: the scan's points (black), the network's
# discs (orange) and the true cylinders (grey).

# %%
from husky_course.planners.discs import DiscMap  # noqa: E402

sim.load(first)  # the player above left another world loaded
first_image = sim.depth(first.start[None])[0]
_, read_discs, _ = DiscMap(discs_model, profile.sim).read(first_image)
scan_points = ego.scan(first_image)
fig, ax = plt.subplots(figsize=(5.5, 4.2))
for x, y, r in first.obstacles:
    ax.add_patch(plt.Circle((x - first.start[0], y - first.start[1]), r, color="0.75"))
for x, y, r in read_discs:
    ax.add_patch(plt.Circle((x, y), r, fill=False, color="tab:orange", lw=2))
ax.plot(scan_points[:, 0], scan_points[:, 1], "k.", ms=3, label="scan points")
ax.plot([], [], "o", mfc="none", mec="tab:orange", mew=2, label="discs the network reads")
ax.plot([], [], "o", color="0.75", label="true cylinders")
ax.legend(fontsize=7, loc="lower left")
ax.set_xlim(-0.5, profile.sim.camera.far + 1)
ax.set_ylim(-3.5, 3.5)
ax.set_aspect("equal")
ax.set_xlabel("x ahead (m)")
ax.set_ylabel("y left (m)")
ax.set_title(f"first image: {len(read_discs)} discs read, validation loss {discs_history.best_val:.3f}",
             fontsize=9)
plt.show()

# %% [markdown]
# ## Every planner of the course on the same held-out worlds
#
# From the paper's Algorithm 1 to the oracle, on the reporting set. The learned look-ahead planners
# use the same `look_ahead` as in chapter 7 (`LOOK_AHEAD`, printed below). `evaluate_stored` keeps
# every run in the artifact store under a key of the planner's whole state, the worlds and the
# library's code, so a planner chapter 7 already ran on these worlds is read back, not run again
# (`husky_course/evaluation/stored.py`).

# %%
LOOK_AHEAD = profile.eval.look_ahead  # as in chapter 7
print(f"LOOK_AHEAD = {LOOK_AHEAD}")
names = ["random", "lookahead", "rnn", "distilled", "heuristic", "mapping", "memory", "discs", "oracle"]
results = {}
for name in names:
    if name in ("lookahead", "rnn", "distilled"):
        p = make_planner(name, profile=profile, look_ahead=LOOK_AHEAD, train=True)
    elif name in ("memory", "discs"):
        p = make_planner(name, profile=profile)  # afresh (the memory student above has run an episode)
    elif name == "oracle":  # the same planner on the same worlds as in the references' table: reuse its run
        results[name] = references["oracle (every obstacle)"]
        continue
    else:
        p = make_planner(name)
    results[name] = evaluate_stored(p, N, REPORT, profile, progress=False, workers=W)
rows = [{"planner": n, "success": r.success_rate,
         "95% interval": f"[{r.success_ci95[0]:.3f}, {r.success_ci95[1]:.3f}]",
         "collisions <= (95%)": r.collision_rate_upper95, "ms / decision": f"{r.ms_per_decision:.2f}"}
        for n, r in results.items()]
display(Markdown(markdown_table(rows)))

# %%
fig, ax = plt.subplots(figsize=(8, 3.4))
s = np.array([results[n].success_rate for n in names])
c = np.array([results[n].success_ci95 for n in names])
ax.bar(names, s, yerr=[s - c[:, 0], c[:, 1] - s], capsize=4, color="tab:blue")
ax.axhline(ever, color="tab:green", ls="--", lw=1, label="perfect perception, seen so far")
ax.set_ylabel("success rate")
ax.set_ylim(0, 1.05)
ax.legend(fontsize=8)
ax.set_title(f"{N} held-out worlds, exact 95% intervals", fontsize=10)
plt.show()

# %%
mem, mapping, distilled, orc = (results[n] for n in ("memory", "mapping", "distilled", "oracle"))
ratio = mem.success_rate / orc.success_rate
text = (
    f"The memory student crosses {mem.success_rate:.1%} of the worlds, {ratio:.0%} of the oracle "
    f"({'meeting' if ratio >= profile.eval.static_goal else 'short of'} the goal of "
    f"{profile.eval.static_goal:.0%}), against {distilled.success_rate:.1%} "
    f"for the distilled planner without memory and {mapping.success_rate:.1%} for the classical mapping "
    f"planner, at {mem.ms_per_decision:.2f} ms per decision against the mapping planner's "
    f"{mapping.ms_per_decision:.2f}. ")
if mem.success_ci95[0] > distilled.success_ci95[1]:
    text += "Memory helps the learned planner: its interval lies above the memoryless one's. "
else:
    text += "On these worlds the intervals of the memory student and the memoryless planner overlap. "
if mem.success_ci95[0] > mapping.success_ci95[1]:
    text += "It also beats the classical map it reads."
elif mem.success_rate < mapping.success_rate:
    text += ("It does not beat the classical planner over the same map"
             + ("; what the network adds is speed, and what it misses is measured below."
                if mem.ms_per_decision < mapping.ms_per_decision else
                ", nor is it faster; what it misses is measured below."))
else:
    text += "It matches the classical planner over the same map within the intervals."
display(Markdown(text))

# %% [markdown]
# The disc planner against the mapping planner, on the same worlds: intervals of two success rates
# answer "could both be the same?" only loosely; the worlds where exactly one of them succeeds
# answer it exactly (a sign test: if both were equally good, each such world would be a fair coin).

# %%
from math import comb  # noqa: E402

disc = results["discs"]
won = sum(a.success and not b.success for a, b in zip(disc.episodes, mapping.episodes, strict=True))
lost = sum(b.success and not a.success for a, b in zip(disc.episodes, mapping.episodes, strict=True))
k, m = min(won, lost), won + lost
p_value = min(1.0, 2 * sum(comb(m, i) for i in range(k + 1)) / 2**m) if m else 1.0
share, goal = disc.success_rate / orc.success_rate, profile.eval.static_goal
verdict = (f"The disc planner crosses {disc.success_rate:.1%} of the reporting worlds "
           f"[{disc.success_ci95[0]:.1%}, {disc.success_ci95[1]:.1%}], {share:.1%} of the oracle's success "
           f"({'meeting' if share >= goal else 'short of'} the goal of {goal:.0%}); the mapping planner "
           f"{mapping.success_rate:.1%}. Of the worlds exactly one of them crosses, the disc planner crosses "
           f"{won} and the mapping planner {lost} (two-sided sign test: p = {p_value:.2g}). ")
verdict += (f"Its collision rate is at most {disc.collision_rate_upper95:.1%} with 95% confidence, at "
            f"{disc.ms_per_decision:.1f} ms per decision (the mapping planner: {mapping.ms_per_decision:.1f} ms; "
            f"{profile.eval.workers} evaluation processes side by side; "
            "`benchmarks/bench_decision.py` times one decision on one thread).")
display(Markdown(verdict))

# %% [markdown]
# ## A certificate after choosing the best
#
# Picking the best of several planners on the same worlds and then quoting its 95% bound is
# optimistic: with `k` candidates, one of them looks good by chance more often than 5% of the time.
# The Bonferroni correction states each bound at confidence `1 - 0.05 / k`, so that all `k` hold
# together with 95%, and the chosen one with them.

# %%
candidates = [n for n in names if n != "oracle"]  # the oracle is privileged: never a candidate
chosen = max(candidates, key=lambda n: results[n].success_rate)
k, r = len(candidates), results[chosen]
collisions = round(r.collision_rate * r.worlds)
plain = clopper_pearson(collisions, r.worlds, 0.95, "upper")[1]
corrected = clopper_pearson(collisions, r.worlds, 1 - 0.05 / k, "upper")[1]
display(Markdown(
    f"The best of the {k} candidates is `{chosen}` ({collisions} collisions in {r.worlds} worlds). "
    f"Its collision rate is at most {plain:.1%} with 95% confidence if it had been chosen in advance, "
    f"and at most **{corrected:.1%}** once the choice among {k} is accounted for."))

# %% [markdown]
# ## How the memory student fails
#
# Its collisions, split by whether the obstacle it hit was rendered by the image at the decision.

# %%
fails = [e for e in mem.episodes if e.collided]
causes = [collision_cause(e, sim) for e in fails]
counts = {c: causes.count(c) for c in ("in view", "out of view", "wall")}
display(Markdown(markdown_table([counts]) if fails else "No collisions on these worlds."))
if fails:
    plotting.draw_collisions(sim, fails, lambda e: f"collided at step {e.n_prims}", most=3)
    plt.show()
    display(Markdown(
        f"{counts['in view']} of its {len(fails)} collisions hit an obstacle the current image showed (a "
        f"prediction error), {counts['out of view']} one the image did not show, where the map had to "
        f"carry it, and {counts['wall']} a side wall."))

# %% [markdown]
# ## Exercises
#
# 1. *Dead reckoning.* A map point is at `(2.0, 0.5)` in the robot's frame. The robot applies
#    primitive 20. Where is the point in the new frame? Use `profile.sim` and
#    `husky_course.sim.primitives.make_library`, then check with
#    `exercises.check_dead_reckoning(profile.sim, (2.0, 0.5), 20, your_point)`.
# 2. *Certificates.* With 3 collisions in 500 worlds, what upper bound can you state for the best of
#    6 planners at 95% overall? Check with `exercises.check_bonferroni(3, 500, 6, your_bound)`.
# 3. Evaluate the mapping planner with `horizon=3` on the tuning set (`evaluate(..., seed=1)`): why
#    does a shorter look-ahead fail more often, though the camera sees as far as its far plane
#    (`profile.sim.camera.far`)?
# 4. The student's map forgets points that fall further behind than `MemoryConfig.map_behind`. What
#    would you expect from a map that forgets everything older than one step? Try it by replacing
#    `memory_planner.map.forget_behind`.
