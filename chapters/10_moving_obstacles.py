# %% [markdown]
# # 10. Moving obstacles
#
# **Learning objectives.** After this chapter you can
#
# - define a world whose obstacles move, with time measured in the robot's own steps, and make both
#   simulators agree on it;
# - plan exactly in space-time with the lattice search of the earlier chapters;
# - measure which planners of the static course still work when the obstacles move, and why;
# - train the memory student on moving worlds and judge it against the space-time oracle.
#
# The paper closes with an open question: "one particularly interesting research topic is the
# application of such a learning based motion planner in environments where obstacles are
# dynamically changing." This chapter answers it in the simulator.
#
# **The moving course.** It is the static course of the same seed, and then some cylinders walk:
# each chosen one moves across the course (along `y`) at a constant speed and bounces off the side
# walls; the others stand still. Time is counted in primitive steps: the robot's `k`-th image is
# taken at time `k`, and the samples of the primitive it then plays back are at times between `k`
# and `k + 1`. Why this model: crossing traffic is what opens and closes the gaps the robot chooses
# between, and what a forward-facing camera sees least of (a cylinder can walk in from outside the
# field of view); motion along `y` only keeps the obstacles' spread along the course, so the course
# is as long in obstacles as the static one; and the same seed gives the same layout at time 0, so
# the two courses are compared world by world. Cylinders pass through one another, which keeps
# every position a closed-form function of the seed and the time.

# %%
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import HTML, Markdown, display

from husky_course.config import get_profile, with_world
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.course.diagnosis import sign_test
from husky_course.course.ladder import moving_ladder
from husky_course.data.calibration import mean_interval, video_lengths
from husky_course.evaluation.analysis import obstacle_hit
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.evaluation.stored import evaluate_stored
from husky_course.imitation.cuts import get_cuts
from husky_course.imitation.dagger import get_memory
from husky_course.planners.base import episode_start
from husky_course.planners.reference import SecondLookPlanner, SeenMotionPlanner, SnapshotPlanner
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator
from husky_course.ui import animation, plotting
from husky_course.ui.plotting import markdown_table

profile = get_profile()
moving = with_world(profile, "moving")
GOAL = profile.eval.moving_goal  # the share of the space-time oracle's success the goal asks
N, REPORT = profile.eval.worlds, profile.eval.seed  # the reporting set: nothing is tuned on it
W = profile.eval.workers
sim, sim_static = FastSimulator(moving.sim), FastSimulator(profile.sim)
wc = moving.sim.world
movers = round(wc.moving_fraction * wc.n_obstacles)
print(f"profile {profile.name}: {N} held-out worlds of evaluation set {REPORT}")
print(f"{movers} of {wc.n_obstacles} cylinders move, at {wc.speed_range[0]}-{wc.speed_range[1]} m per step "
      f"(the robot advances {moving.sim.primitives.advance} m per step)")

# %% [markdown]
# ## The world over ten steps
#
# One held-out world with the space-time oracle driving (below). Moving cylinders are purple, their
# arrows show where they will be one step later. Scrub through the ten steps: the oracle threads
# between cylinders that are not yet where it passes, or no longer there.

# %%
world_seed = int(eval_world_seeds(1, REPORT)[0])
shown = run_episode(make_planner("oracle"), sim, world_seed)
display(HTML(animation.course_player(sim, shown, title="space-time oracle, ")))

# %% [markdown]
# ## Both simulators, at the right times
#
# The fast simulator places the cylinders where they are at each query's time: per image for depth,
# per recorded sample for contact. The PyBullet reference moves the bodies themselves
# (`resetBasePositionAndOrientation`) before every image and every sample. The test suite renders
# views and plays primitives back at times it draws at random and requires the same pixels (within
# the float precision of PyBullet's depth buffer) and the same contact outcomes
# (`tests/test_fast_vs_pybullet.py`); here is one view at three times, from the start pose.

# %%
world = sim.load(world_seed)
fig, axes = plt.subplots(1, 3, figsize=(10, 3))
for ax, t in zip(axes, (0, 2, 4), strict=True):
    plotting.show_depth(sim.depth(world.start[None], t)[0], ax, f"from the start pose, time {t}")
plt.show()

# %% [markdown]
# The motion model, checked on this world at 100 times per step: a moving cylinder travels at its
# constant speed, reflects off a side wall, and is a closed-form function of the seed and the time.

# %%
# NBVAL_CHECK_OUTPUT
times = np.linspace(0, moving.sim.max_primitives, 100 * moving.sim.max_primitives + 1)
at = world.obstacles_at(times)  # (times, cylinders, 3)
radii, walkers = world.obstacles[:, 2], world.moving
standing = np.setdiff1d(np.arange(len(radii)), walkers)
speed = np.abs(np.diff(at[:, walkers, 1], axis=0)) / np.diff(times)[:, None]
print(f"{len(walkers)} of {len(radii)} cylinders move")
print("every cylinder stays between the walls:", bool((np.abs(at[..., 1]) <= world.wall_y - radii + 1e-9).all()))
print("the others never move:", bool((at[:, standing] == world.obstacles[standing]).all()))
print("no mover ever exceeds its speed:", bool((speed <= np.abs(world.speeds[walkers]) + 1e-9).all()))
print("the same seed gives the same positions:",
      bool(np.array_equal(sim.load(world_seed).obstacles_at(times), at)))

# %% [markdown]
# ## Calibration: the random policy on both courses
#
# The static course was calibrated so that the random policy survives about as many primitives per
# video as the paper reports. The same videos (same worlds, same random primitives, the calibration's
# own collection seed) on the moving course:

# %%
cal = profile.calibration
lengths = {kind: video_lengths(p.sim, cal.videos, cal.seed) for kind, p in (("static", profile), ("moving", moving))}
rows = []
for kind, ls in lengths.items():
    mean, lo, hi = mean_interval(ls)
    rows.append({"course": kind, "videos": len(ls), "mean primitives per video": mean,
                 "95% interval": f"[{lo:.2f}, {hi:.2f}]"})
display(Markdown(markdown_table(rows)))
(ms, ls_, hs), (mm, lm, hm) = (mean_interval(x) for x in lengths.values())
overlap = lm <= hs and ls_ <= hm
display(Markdown(
    f"The paper's random videos last {cal.target} primitives. On the static course the random policy "
    f"survives {ms:.2f}, on the moving one {mm:.2f}: "
    + ("the two intervals overlap, so a random walk does not notice the motion at this resolution. "
       if overlap else f"the moving course is {'harder' if mm < ms else 'easier'} for a random walk. ")
    + "A random policy does not aim for gaps, so it is the planners below that tell the courses apart."))

# %% [markdown]
# ## Planning in space-time
#
# The robot cannot wait: every primitive takes one step, so every state at depth `k` of the lattice
# search (chapter 7) is reached at time `k`, and the lattice is already a lattice in space-time. On
# the moving course each edge is checked against the cylinders where they are at its samples'
# times; nothing else changes. The test suite checks this against brute force (every sequence of
# primitives played back in the simulator) on small cases.
#
# Four privileged planners frame everything else (analysis tools, never candidates). The
# **space-time oracle** knows every cylinder and its motion. **Seen, with motion** replans in
# space-time at every step over the cylinders some image has rendered so far, with their true
# motion: a reference for a camera-based planner that perceives perfectly, motion included (a
# reference, not a ceiling: it takes space no image has shown as free, and a planner cautious there,
# or one that learns where cylinders tend to walk, is bounded by neither it nor the next).
# **Seen, motion from its second look** is the same, except that a cylinder seen for the first time
# is taken as standing where it is: one image shows where a cylinder is, not where it goes, so this
# is what a planner reading motion off images, and otherwise perfect, reaches when it takes a first
# sight as standing. The **snapshot** planner knows where every cylinder is *now* (no field of view
# to limit it), replans at every step, but assumes they stand still: perfect perception of the
# present, without motion.

# %% [markdown]
# ## Every planner on the moving course
#
# On the reporting set (the same held-out worlds on both courses). The static planners run as they
# are. Two planners read motion off successive images, with nothing privileged: the scans are their
# own images, the displacement their own primitive.
#
# **Motion from successive images** (`husky_course.planners.motion`). The robot cuts each scan into
# pieces of surface (and cuts again where two arcs meet). Each piece is located by the circle that
# best fits its points (its radius held near the course's typical radius): a cylinder gives the
# camera only a few columns, and which ones changes as the robot moves, so the mean of a piece's
# points jumps by a good part of a radius from one image to the next while the fitted centre moves
# only with the cylinder. Each located piece joins a *track*: the sightings of one cylinder in the
# last four images, moved into the current frame by dead reckoning. Its velocity is the weighted
# line through them, the near looks (many columns, centimetres) counting more than the far ones (one
# or two columns, a column's width). The robot also knows the course's rule of motion: a cylinder
# either stands or walks at a speed in a known range. So a velocity that the looks' precision
# cannot tell from zero as well as from a walk is read as standing (a standing cylinder no longer
# seems to drift because two coarse looks disagree), and a walk is clipped into the range. A piece
# seen for the first time has no velocity yet, and it is marked as *seen once*. One image still says
# something about it (`husky_course.planners.arrivals`): each speed the course allows, either way,
# and standing, is a guess at where the cylinder stood one step ago, and a guess is ruled out when
# the previous image looked *through* that place. If standing is ruled out, the cylinder walked
# into free space; when every guess left walks one way, it gets their mean speed. Otherwise it is
# taken as standing until the next image. The planners without learning (`tracking`) and with
# learned discs (`discs`) both use this rule; the memory student reads *seen once* instead.
# The disc planner's tracks locate a cylinder by its network's disc centre instead of the fitted
# circle, which the network places more precisely across the view.
# The disc planner reads more of those images. Its network gives a first sight's centre and radius,
# so each guess predicts the depth of every column the cylinder would have covered in each of the
# last three images. A column that saw through it rules the guess out. A column that saw its front
# there, within 0.1 m, supports it; a nearer depth hid it, and says nothing. Among the guesses left,
# those with the most supporting columns decide, when they agree on standing or on a direction.
# A cylinder half hidden last time, or hidden last time and seen the time before, now gets its walk.
# `benchmarks/exp_moving_evidence.py` compares it with the centre-column rule on the tuning set,
# and offers the same reading to the tracker, whose circles are fitted with the course's mean radius.
# The episode's first decision has no earlier image at all: every cylinder in view is a first
# sight, and no planner that reads motion off its own images can know yet which of them walk.
# `benchmarks/exp_moving_start.py` counts the failures already lost there, and measures two ways
# around it on the tuning set: drawing the course's rule of motion for those cylinders many times
# and taking the first primitive that survives longest on average (the setting `first_samples`,
# within the course's rules), and a look before the start, while the robot stands on the start
# line (a change of the course's rules, not a planner).
# `benchmarks/exp_moving_tracker.py` measures the estimate against the truth, and
# `benchmarks/exp_moving_ladder.py` how far each planner would get if its map were told the true
# motion, rung by rung (where its tracks know it, from a cylinder's second image on, always).
#
# **The map walks.** Both planners keep the mapping planner's map of everything seen (chapter 8),
# each point now carrying its velocity and walking on after every step, also when the camera no
# longer sees it. The **mapping planner with motion** (`tracking`, no learning) plans over it with
# the space-time lattice search: a walking point is checked where it will be at each sample's time.
# A walking cylinder turns back at a side wall. The robot does not know where in the course it
# started, but it sees the walls: the disc planner reads their faces off the points it remembers
# that line up along the course (`husky_course.planners.walls`), and its walking discs bounce off
# them, in its map and in its search. The tracker's walking points bounce by the same rule, its
# faces read off the points of its long pieces, so that neither planner holds a reading of the
# course the other lacks (`benchmarks/exp_moving_walls.py` compares both with walks in a straight
# line on the tuning set). A walker that turned at a wall between two looks leaves a folded line of
# looks, which a straight line reads as standing; once the faces are known, both planners' tracks
# unfold it where a fold fits the looks clearly better (`TrackingConfig.bounce_gain`).
# **What the disc planner doubts.** Its map holds one guess of every motion, and the planner knows
# two ways in which that guess may be wrong: a first sight the earlier images leave undecided may
# stand or walk, and a tracked walker's speed comes from a few coarse looks. So at every decision it
# draws versions of the motion (`ArrivalsConfig.samples` of them): each undecided first sight walks
# as the course's rule of motion allows, among the walks no earlier column saw through, and each
# tracked walker at its track's speed plus a normal error (spread `ArrivalsConfig.speed_sigma`). It
# searches every version and takes the first primitive whose plans survive the most steps on
# average. An average, unlike a worst-case band around every doubtful cylinder, keeps a tight pass
# that most versions survive; the measurements on the tuning set are in `ArrivalsConfig`. Most
# decisions end in a tie: several primitives survive every version to the horizon. The tie goes to
# the one whose plan keeps the most clearance in its worst version, then on average over the
# versions, not to the one its single guess of the motion ranks first: a pass that stays wide
# whatever the doubted cylinders do (`benchmarks/exp_moving_ties.py`). What still ties goes to the
# first primitive after which its safe plans reach the most places at the horizon's end, on average
# over the versions: the move that keeps the most ways open for what the camera has not yet shown
# (`ArrivalsConfig.ties`).
# Whether those doubts have the right size, `benchmarks/exp_moving_beliefs.py` measures along the
# planner's own runs, each belief beside the truth (privileged, an analysis tool).
# The tracker plans on its map's single guess.
# Telling such rules apart takes care: a rule that changes many of the planner's choices moves its
# success on 1,000 worlds by a couple of points either way at random (the search's own tie-break,
# mirrored, does). `benchmarks/exp_moving_paired.py` therefore also judges a rule decision by
# decision, from the *same* states: the planner as it is drives, the variant runs beside it on the
# same images, and each choice is judged in the true world (does a way through remain after it?).
# `benchmarks/exp_moving_memory.py` prices the map's memory the same way, with shadows told part of
# the truth: the cylinders it has lost, how each was lost, and where its remembered discs really are.
# Most of the lost were neighbours whose pieces the cut had joined, and a shadow whose pieces are cut
# exactly where two cylinders meet is worth as much as one told every lost cylinder: that is what the
# disc planner's cut network (chapter 8) learns to do.
# A disc is also dropped when its cylinder is still there, walking: an image sees through the place
# where the map last put it, most often a first sight that left the view before a second image could
# show where it went. The disc planner keeps such a disc as a *ghost*: one guess per walk the course's
# motion model allows, starting from where its disc was last made; each guess is ruled out once an
# image sees through it, and every version of the motion stands the ghost at one guess still open.
# Which new disc is which cylinder decides when a ghost is made and when it ends, and the camera's own
# answer is the tracks. A new disc that continues the dropped disc's track is its cylinder, however far
# it is from where the map expected it. A new disc that continues another cylinder's track is not.
# Where the ghosts stand matters less than which cylinder they belong to; the measurements are in
# `ArrivalsConfig.ghosts`, `benchmarks/exp_moving_drift.py` and `benchmarks/exp_moving_identity.py`.
# The **memory student** of chapter 8 is trained again by the same DAgger recipe, on moving worlds,
# from the space-time oracle; it reads four rasters of the walking map: where its points are now,
# one step later, *when the robot reaches them*, and which of them were seen only once. Every
# primitive advances the same distance per step at a constant forward speed, so a point `x` metres
# ahead is reached `x / advance` steps from now: moved by that many steps of its walk, the moving
# course becomes a static one (up to the bounces and the cylinders' own width), the kind of map the
# static student already reads. The points seen once have no velocity yet; the tracker takes them as
# standing unless they walked in, while the student learns from its labels how much room they need. The memory student of
# chapter 8, trained on the static course, runs beside it as it is.

# %%
LOOK_AHEAD = profile.eval.look_ahead  # as in chapters 7 and 8
student_moving = get_memory(moving, progress=False)  # `python -m husky_course train memory --world moving`
get_cuts(profile, progress=False)  # the disc planner's cut network (`python -m husky_course train cuts`)
display(Markdown(markdown_table([
    {"round": r["round"], "who drives": r["acting"], "states added": r["states"],
     "success in its training worlds": r["success_in_its_worlds"]} for r in student_moving.rounds])))


# %% [markdown]
# What the moving-trained student reads at the third step of the world above (the oracle driving):
# the depth image, its walking map now, one step ahead, where each point will be when the robot
# gets there, and the points seen by one image only.

# %%
student = make_planner("memory", profile=moving)
student.reset(episode_start(student, sim, world_seed, shown.poses[0], moving.sim.max_primitives))
for k in range(3):
    image, grid = student.prepare(sim.depth(shown.poses[k][None], k)[0])
    student.observe(shown.actions[k], None)
fig, axes = plt.subplots(1, 5, figsize=(13, 2.9))
plotting.show_depth(image, axes[0], "depth image, time 2")
titles = ("its map, now", "one step ahead", "when it gets there", "seen once")
for ax, g, title in zip(axes[1:], grid, titles, strict=True):
    ax.imshow(g, cmap="Greys", vmin=0, vmax=1)
    ax.set_title(title, fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
plt.show()


def build(name: str, course) -> object:
    """The planner ``name``; learned ones trained on the static course unless said otherwise."""
    if name == "distilled":
        return make_planner(name, profile=profile, look_ahead=LOOK_AHEAD)
    if name == "memory (static-trained)":
        return make_planner("memory", profile=profile)
    if name == "memory (moving-trained)":
        return make_planner("memory", profile=moving)
    if name == "snapshot":
        return SnapshotPlanner()
    if name == "seen, with motion":
        return SeenMotionPlanner()
    if name == "seen, motion from its second look":
        return SecondLookPlanner()
    if name == "mapping, with motion":
        return make_planner("tracking", config=course.sim)
    if name == "discs":  # chapter 8's learned discs; on the moving course they walk, read as the tracker reads
        return make_planner("discs", profile=profile, config=course.sim)
    return make_planner(name, **({"config": course.sim} if name == "heuristic" else {}))


names = ["random", "heuristic", "mapping", "mapping, with motion", "distilled", "memory (static-trained)",
         "memory (moving-trained)", "discs", "snapshot", "seen, motion from its second look", "seen, with motion",
         "oracle"]
on_static = ["heuristic", "mapping", "distilled", "memory (static-trained)", "discs", "oracle"]  # tracking = mapping
res = {n: evaluate_stored(build(n, moving), N, REPORT, moving, progress=False, workers=W) for n in names}
res_static = {n: evaluate_stored(build(n, profile), N, REPORT, profile, progress=False, workers=W)
              for n in on_static}
rows = [{"planner": n, "success (moving)": r.success_rate,
         "95% interval": f"[{r.success_ci95[0]:.3f}, {r.success_ci95[1]:.3f}]",
         "collisions <= (95%)": r.collision_rate_upper95, "mean prims": r.mean_prims,
         "success (static)": f"{res_static[n].success_rate:.3f}" if n in res_static else "-"}
        for n, r in res.items()]
display(Markdown(markdown_table(rows)))

# %%
fig, ax = plt.subplots(figsize=(12.5, 3.9))
x = np.arange(len(names))
s = np.array([res[n].success_rate for n in names])
c = np.array([res[n].success_ci95 for n in names])
ax.bar(x, s, yerr=[s - c[:, 0], c[:, 1] - s], capsize=4, color="tab:purple", label="moving course")
st = [res_static[n].success_rate if n in res_static else np.nan for n in names]
ax.scatter(x, st, marker="_", s=400, color="k", zorder=5, label="same planner, static course")
labels = []
for label in names:  # wrapped, so that twelve fit side by side
    for cut, new in ((" (", "\n("), (", ", ",\n"), ("-", "-\n"), (" from ", "\nfrom ")):
        label = label.replace(cut, new)
    labels.append(label)
ax.set_xticks(x, labels, fontsize=8)
ax.set_ylabel("success rate")
ax.set_ylim(0, 1.05)
ax.legend(fontsize=8)
ax.set_title(f"{N} held-out worlds, exact 95% intervals", fontsize=10)
plt.show()

# %%
orc, snap, seen = res["oracle"], res["snapshot"], res["seen, with motion"]
second = res["seen, motion from its second look"]
stud, old = res["memory (moving-trained)"], res["memory (static-trained)"]
ratio = stud.success_rate / orc.success_rate
track = res["mapping, with motion"]
drops = {n: res_static[n].success_rate - res[n].success_rate for n in on_static if n != "oracle"}
worst = max(drops, key=drops.get)
# the same worlds on both courses: worlds a planner crosses only when still against only when moving,
# an exact sign test each, at 0.05 / k (Bonferroni) so that the k verdicts hold together with 95%
paired = {}
for n in drops:
    by_seed = {e.world_seed: e.success for e in res[n].episodes}
    paired[n] = sign_test(np.array([e.success for e in res_static[n].episodes]),
                          np.array([by_seed[e.world_seed] for e in res_static[n].episodes]))
alpha = 0.05 / len(paired)
loses = [n for n, (a, b, p) in paired.items() if a > b and p < alpha]
gains = [n for n, (a, b, p) in paired.items() if b > a and p < alpha]
display(Markdown(markdown_table(
    [{"static planner": n, "success, static": res_static[n].success_rate, "success, moving": res[n].success_rate,
      "worlds crossed only when still": a, "only when moving": b, "sign test p": f"{p:.2g}"}
     for n, (a, b, p) in paired.items()])))
print(f"Bonferroni over {len(paired)} planners: each verdict at p < {alpha:.3g}")
uncrossable, collided = round((1 - orc.crossable_rate) * orc.worlds), round(orc.collision_rate * orc.worlds)
text = (
    f"The space-time oracle crosses {orc.success_rate:.1%} of the moving worlds; it reports {uncrossable} of "
    f"the {orc.worlds} uncrossable and collides in {collided}. Knowing only where every cylinder is now, the "
    f"snapshot planner crosses {snap.success_rate:.1%}; knowing instead the motion of every cylinder the "
    f"camera has shown, {seen.success_rate:.1%}. Perceiving motion is worth "
    f"{seen.success_rate - snap.success_rate:.1%} of the worlds, what the camera never shows "
    f"{orc.success_rate - seen.success_rate:.1%}: "
    + ("the camera shows enough, and what a camera-based planner must learn here is the motion. "
       if seen.success_rate - snap.success_rate > orc.success_rate - seen.success_rate else
       "the field of view costs more than the motion. ")
    + f"Knowing a cylinder's motion only from its second image on, as a planner reading motion off images "
    f"must (one image shows where a cylinder is, not where it goes), perception otherwise perfect: "
    f"{second.success_rate:.1%}, {second.success_rate / orc.success_rate:.0%} of the oracle. "
    + (f"Every one of the {len(paired)} static planners loses measurably on the moving course"
       if len(loses) == len(paired) else
       f"{len(loses)} of the {len(paired)} static planners lose measurably on the moving course"
       + (f" ({', '.join(f'`{n}`' for n in loses)})" if loses else "")
       + (f", {len(gains)} gain ({', '.join(f'`{n}`' for n in gains)})" if gains else "")
       + ("; for the others the sign test cannot tell the courses apart" if len(loses) + len(gains) < len(paired)
          else ""))
    + " (sign tests on the same worlds, 95% overall)"
    + (f"; `{worst}` drops most, by {drops[worst]:.1%} of the worlds. " if drops[worst] > 0 else
       ": none of them crosses fewer worlds on the moving course. "))
text += (
    f"The memory student trained on moving worlds crosses {stud.success_rate:.1%}, {ratio:.0%} of the "
    f"oracle, {'meeting' if ratio >= GOAL else 'short of'} the goal of {GOAL:.0%}; the static-trained student "
    f"crosses {old.success_rate:.1%}. ")
if stud.success_ci95[0] > old.success_ci95[1]:
    text += "Training on moving worlds helps: the two intervals do not overlap. "
else:
    text += "The two students' intervals overlap: training on moving worlds has not measurably helped. "
if stud.success_ci95[1] < snap.success_ci95[0]:
    text += "The moving-trained student stays below the snapshot planner, which sees everything now."
elif stud.success_ci95[0] > snap.success_ci95[1]:
    text += ("It beats the snapshot planner, which sees every cylinder now but not its motion: it has "
             "learned something of the motion from successive images.")
else:
    text += ("It is level with the snapshot planner (the intervals overlap), which sees every cylinder now "
             "but not its motion: whatever it infers of the motion does not yet show.")
text += (
    f" The mapping planner with motion, which reads the same walking map and searches it instead of "
    f"learning, crosses {track.success_rate:.1%} ({track.success_rate / orc.success_rate:.0%} of the oracle; on "
    f"the static course it is the mapping planner): "
    + ("the student has not learned all that its inputs allow." if stud.success_ci95[1] < track.success_ci95[0]
       else "the student does better than a search over its inputs." if stud.success_ci95[0] > track.success_ci95[1]
       else "level with the student (the intervals overlap).")
)
disc = res["discs"]
only_disc, only_track, p_disc = sign_test(np.array([e.success for e in disc.episodes]),
                                          np.array([e.success for e in track.episodes]))
text += (
    f" Chapter 8's disc planner, its network trained on static views and its discs walking with velocities "
    f"read by the tracker's tracks (which follow its discs' centres), crosses {disc.success_rate:.1%} ({disc.success_rate / orc.success_rate:.0%} of the oracle, "
    f"{'meeting' if disc.success_rate >= GOAL * orc.success_rate else 'short of'} the goal of {GOAL:.0%}): "
    + ("above the tracker, with intervals that do not overlap" if disc.success_ci95[0] > track.success_ci95[1]
       else "more than the tracker, though the two intervals overlap" if disc.success_rate > track.success_rate
       else "no more than the tracker")
    + f". On the same worlds it wins {only_disc} that the tracker loses and loses {only_track} that the tracker "
    f"wins (exact sign test p = {p_disc:.2g}: "
    + ("a difference the worlds show, at 5%)." if p_disc < 0.05 else "no difference the worlds can show at 5%).")
)
display(Markdown(text))

# %% [markdown]
# ## What limits the disc planner: a ladder on the tuning set
#
# The best learned planner here is the disc planner. Where does it lose? Its own map is told more
# and more of the truth, on the tuning set (never the reporting set): the true motion of the
# cylinders its tracks see for the first time (one image shows where a cylinder is, not where it
# goes); the true motion of every disc; then, in place of its discs, every cylinder any image has
# rendered so far, exactly, with its motion (its search and its wall points unchanged). The last
# rung knows what the perfect-perception reference knows, and differs from it only in the search.
# These rungs are privileged references, not bounds: each tells the planner something no camera
# can, and a planner could also do better by driving differently.

# %%
N_TUNE, TUNE = profile.eval.tuning_worlds, profile.eval.tuning_seed  # the tuning set
rungs = {name: evaluate_stored(p, N_TUNE, TUNE, moving, progress=False, workers=W)
         for name, p in moving_ladder(profile)}
display(Markdown(markdown_table([
    {"rung (moving course, tuning set)": k, "success": r.success_rate,
     "95% interval": f"[{r.success_ci95[0]:.3f}, {r.success_ci95[1]:.3f}]"} for k, r in rungs.items()])))
rate = [r.success_rate for r in rungs.values()]  # discs, first sights told, every disc told, seen exactly, reference
parts = {"the motion of its first sights": rate[1] - rate[0],
         "the motion of the discs it had tracked": rate[2] - rate[1],
         "what its map remembers of the cylinders it has seen, and where": rate[3] - rate[2],
         "its search against the oracle's": rate[4] - rate[3]}
top = max(parts, key=parts.get)
display(Markdown(
    f"On {N_TUNE} tuning worlds the disc planner crosses {rate[0]:.1%}. Told the true motion of its first "
    f"sights alone it crosses {rate[1]:.1%}; of every disc, {rate[2]:.1%}; handed every cylinder seen so far, "
    f"exactly, {rate[3]:.1%}; the reference that knows as much and searches as the oracle does, {rate[4]:.1%}. "
    + "Step by step, in points of success: " + "; ".join(f"{k}, {100 * v:+.1f}" for k, v in parts.items())
    + f". The largest step is {top}"
    + (": one image shows where a cylinder is, not where it goes (`benchmarks/exp_moving_first_sight.py` "
       "measures what a network reading the previous image adds to the arrivals rule)."
       if top == "the motion of its first sights" else ".")
    + " (Finer rungs, on 300 tuning worlds: `python benchmarks/exp_moving_ladder.py --planners discs`.)"))

# %% [markdown]
# ## How the moving-trained student fails
#
# Its collisions, split by what it hit: a moving cylinder, a standing one, or a side wall. The
# cylinders are drawn where they stood when the colliding primitive started.

# %%
fails = [e for e in stud.episodes if e.collided]
hits = [obstacle_hit(e, sim) for e in fails]
kinds = ["wall" if i < 0 else ("moving cylinder" if i in w.moving else "standing cylinder") for i, w, _ in hits]
counts = {k: kinds.count(k) for k in ("moving cylinder", "standing cylinder", "wall")}
display(Markdown(markdown_table([counts]) if fails else "No collisions on these worlds."))
cylinder_hits = counts["moving cylinder"] + counts["standing cylinder"]
if cylinder_hits:
    share_movers = movers / wc.n_obstacles
    lo, hi = clopper_pearson(counts["moving cylinder"], cylinder_hits)  # exact 95% interval
    text = (f"{counts['moving cylinder']} of the {cylinder_hits} cylinders it hits move "
            f"({counts['moving cylinder'] / cylinder_hits:.0%}, exact 95% interval [{lo:.0%}, {hi:.0%}]), "
            f"while {share_movers:.0%} of the cylinders move: ")
    if lo > share_movers:
        text += ("moving cylinders are over-represented among what it hits. That points to the motion, without "
                 "proving that anticipating it is what fails: a walking cylinder also crosses more of the course "
                 "than a standing one, so any planner meets it more often.")
    elif hi < share_movers:
        text += "moving cylinders are under-represented among what it hits."
    else:
        text += ("the interval contains their share, so these collisions cannot tell whether the moving "
                 "cylinders are what it handles worst.")
    display(Markdown(text))
if fails:
    mover_fails = [e for e, k in zip(fails, kinds, strict=True) if k == "moving cylinder"][:1]
    if mover_fails:
        display(HTML(animation.course_player(sim, mover_fails[0], title="moving-trained student, ")))

# %% [markdown]
# ## Exercises
#
# 1. *Where is a moving cylinder?* Take the world above (`world_seed`) and one of its moving cylinders
#    (`sim.world.moving`). From its start `world.obstacles[i]`, its speed `world.speeds[i]` and the
#    walls at `|y| = world.wall_y`, work out where it is at time 3.5 (it bounces when its surface
#    touches a wall). Check with `exercises.check_mover_position(world_seed, moving.sim, i, 3.5, your_y)`.
# 2. *Time along a primitive.* The primitive started at step 4 is recorded as
#    `moving.sim.primitives.samples` poses. At what time is its sample 25 checked for contact? Check
#    with `exercises.check_sample_time(4, 25, moving.sim.primitives.samples, your_t)`.
# 3. The snapshot planner replans at every step over the cylinders where they are now. Give it the
#    cylinders where they will be one step later instead (`world.obstacles_at(t + 1)`) and evaluate
#    it on the tuning set (`evaluate(..., seed=1)`): how much of the gap to the oracle does one step
#    of foresight close?
# 4. Where on the moving course would you expect the static-trained memory student's map to mislead
#    it? (Hint: what does the map keep of a cylinder that has walked out of the field of view?)
# 5. *A cylinder behind its arc.* `arc, r = exercises.cylinder_arc(0, moving.sim)` gives the scan
#    points (robot frame) one cylinder of radius `r` gave the camera. Find its centre: every point
#    lies at distance `r` from it, and it is behind the points as the camera sees them (two points
#    already fix it). How far from it is the points' mean, and why does that make the mean a poor
#    way to read a cylinder's motion from two images? Check with
#    `exercises.check_arc_centre(arc, r, your_centre, moving.sim)`.
