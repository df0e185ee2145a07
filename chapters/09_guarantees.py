# %% [markdown]
# # 9. Guarantees: a certificate from the training worlds
#
# **Learning objectives.** After this chapter you can
#
# - explain what a PAC-Bayes generalization bound promises, and what it costs: a prior fixed in
#   advance, a *distribution* over policies, and a KL divergence between the two;
# - compute the bound from first principles: the Bernoulli KL, its inverse by bisection, and the
#   sample-convergence bound on a training cost that is itself estimated by sampling policies;
# - certify the memory student of chapter 8 from its training worlds alone, then check the
#   certificate against far more worlds it never saw, beside the test-set bound of chapter 7;
# - say how many worlds a certificate of a given tightness needs, and run that many on a cluster.
#
# The paper's data came from "a policy based on PAC-Bayes framework" (its abstract), the framework
# of the lab the project grew from. The lab's vision-based planners (outside the paper; their code
# is public as `irom-lab/PAC-Vision-Planning`) report a bound computed from training environments
# alone and compare it with the cost measured on new ones. Until now this course offered only the
# second kind of statement: a Clopper–Pearson bound from held-out worlds (chapters 7 and 8), which
# needs worlds that nothing was fitted on. A PAC-Bayes certificate is computed from the worlds the
# policy was fitted on, at a price stated in the bound: how far the fitted policy moved from a
# prior chosen before those worlds were seen.

# %%
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Markdown, display

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.evaluation.certificate import get_certificate
from husky_course.evaluation.pac_bayes import (
    bernoulli_kl,
    certificate,
    kl_inverse,
    pac_bayes_kl_bound,
)
from husky_course.evaluation.statistics import clopper_pearson
from husky_course.ui.plotting import markdown_table

profile = get_profile()
g = profile.guarantee
print(f"profile {profile.name}: N = {g.worlds} certificate training worlds, {g.heldout_worlds} held-out worlds "
      f"(evaluation set {g.heldout_set}), delta = {g.delta}, delta' = {g.delta_prime}")

# %% [markdown]
# ## The bound, from first principles
#
# A *stochastic policy* is a distribution $P$ over network weights: at the start of an episode one
# weight vector $w \sim P$ is drawn and the robot drives with it. Its cost $C(P)$ is the probability,
# over worlds from the course's distribution and over $w$, that the robot does not cross. From $N$
# training worlds $S$ and a prior $P_0$ chosen *before* $S$ is seen, Maurer's PAC-Bayes-kl bound (the
# form the lab uses) says that with probability at least $1-\delta$ over the draw of $S$, **for every
# $P$ at once**,
#
# $$ \mathrm{kl}\big(C_S(P)\,\|\,C(P)\big) \le \frac{\mathrm{KL}(P\,\|\,P_0) + \log\frac{2\sqrt N}{\delta}}{N}, $$
#
# where $C_S(P)$ is the expected cost on the training worlds and $\mathrm{kl}(q\|p)$ the KL divergence
# between Bernoulli($q$) and Bernoulli($p$). "For every $P$ at once" is what lets the posterior be
# fitted on $S$ itself: the price of fitting is $\mathrm{KL}(P\|P_0)$, paid in the numerator.
#
# The bound is on $\mathrm{kl}$, not on $C(P)$; to read off $C(P)$ we need the largest $p$ with
# $\mathrm{kl}(q\|p) \le c$. $\mathrm{kl}(q\|p)$ is zero at $p=q$ and increases on $[q, 1]$, so
# bisection finds it: `kl_inverse` returns the upper end of its last bracket, so rounding never
# weakens a bound.

# %%
# NBVAL_CHECK_OUTPUT
for q, c in [(0.2, 0.01), (0.2, 0.001), (0.0, 0.01), (0.5, 0.1)]:
    p = kl_inverse(q, c)
    print(f"kl_inverse(q={q}, c={c}) = {p:.6f}   check: kl(q || p) = {bernoulli_kl(q, p):.6f}")

# %%
fig, ax = plt.subplots(figsize=(6, 3.2))
ps = np.linspace(0.2, 0.6, 400)
ax.plot(ps, [bernoulli_kl(0.2, p) for p in ps], label="kl(0.2 || p)")
for c, color in ((0.01, "tab:orange"), (0.03, "tab:red")):
    ax.axhline(c, color=color, lw=1, ls="--")
    ax.axvline(kl_inverse(0.2, c), color=color, lw=1, label=f"kl_inverse(0.2, {c})")
ax.set_xlabel("p (true cost)")
ax.set_ylabel("nats")
ax.set_ylim(0, 0.06)
ax.legend(fontsize=8)
ax.set_title("Inverting the Bernoulli KL: the largest true cost consistent with the bound", fontsize=9)
plt.show()

# %% [markdown]
# **Sample convergence.** $C_S(P)$ is an expectation over weights, which we cannot compute exactly;
# we estimate it by running drawn weights. The lab draws $L$ weight vectors and runs each on all $N$
# worlds, giving $L$ independent averages. We draw $L$ *fresh* vectors for every world instead
# (`draws_per_world`): then all $L N$ costs are independent given the worlds, each in $[0, 1]$, and
# their mean has expectation $C_S(P)$. Hoeffding's inequality in its kl form holds for independent
# variables that need not be identically distributed, so with probability at least $1-\delta'$,
# $C_S(P) \le \mathrm{kl}^{-1}\big(\hat C_S, \log(2/\delta')/(LN)\big)$ (the two-sided constant
# $\log(2/\delta')$, slightly conservative). Together: $C(P)$ is bounded with probability at least
# $1-\delta-\delta'$. (Maurer's constant $2\sqrt N$ is proven for $N \ge 8$; the code refuses fewer.)
#
# **The choices, and why** (the numbers are the configuration's, printed below). Most of the
# confidence budget goes to the PAC-Bayes term, whose slack grows only with $\log(1/\delta)$. $N$ is
# sized so that the whole certificate builds within the book's time budget; the section "How many
# worlds" shows what a larger $N$ would buy. Nothing here was tuned on the certificate's worlds or on
# its held-out set: the prior's scale, $N$, the fitting settings and the seeds were fixed before
# either was run (a setting picked as the best of several would have to share $\delta$ among them).

# %%
from husky_course.imitation.dagger import round_worlds
from husky_course.imitation.posterior import certificate_worlds

dagger_worlds = {int(s) for r in range(profile.memory.rounds) for s in round_worlds(profile, r)}
cert_worlds = set(certificate_worlds(profile).tolist())
print(f"delta = {g.delta}, delta' = {g.delta_prime}: confidence {1 - g.delta - g.delta_prime:.1%}; "
      f"{g.draws_per_world} weight draw(s) per world")
print(f"certificate training worlds: collection seed {g.collection_seed}, {len(cert_worlds)} worlds; "
      f"the prior's DAgger worlds: collection seed {profile.memory.collection_seed}, {len(dagger_worlds)} worlds; "
      f"shared: {len(dagger_worlds & cert_worlds)}")
print(f"held-out worlds: evaluation set {g.heldout_set} (chapters 7 and 8 report on set {profile.eval.seed}, "
      f"tune on set 1)")

# %%
fig, ax = plt.subplots(figsize=(6, 3.2))
ns = np.unique(np.geomspace(100, 100_000, 40).astype(int))
for kl in (0.0, 10.0, 100.0):
    ax.plot(ns, [pac_bayes_kl_bound(0.2, kl, int(n), g.delta) for n in ns], label=f"KL = {kl:g} nats")
ax.axhline(0.2, color="0.5", lw=1, ls=":", label="training cost 0.2")
ax.set_xscale("log")
ax.set_xlabel("N, training worlds")
ax.set_ylabel("bound on the true cost")
ax.legend(fontsize=8)
ax.set_title(f"The PAC-Bayes-kl bound for a training cost of 0.2 (delta = {g.delta})", fontsize=9)
plt.show()

# %% [markdown]
# ## The prior and the posterior
#
# The policy is chapter 8's memory student with one change: the weights of its output layer (the
# last linear map, hidden units to one value per primitive) are drawn from a diagonal Gaussian at the
# start of each episode; every other weight stays as DAgger trained it.
#
# - **Prior** $P_0 = \mathcal N(w_0, s_0^2 I)$: $w_0$ is the output layer as DAgger trained it on its
#   own worlds, and $s_0$ is `GuaranteeConfig.prior_scale` times the RMS of $w_0$. Both are fixed
#   before any certificate world is seen, which is all the bound asks of a prior: weights trained on
#   a separate split of worlds.
# - **Posterior** $P = \mathcal N(\mu, \mathrm{diag}(s^2))$, fitted on $S$: the student drives in the
#   first `finetune_worlds` of the training worlds, every state it visits is labelled with the
#   simulator's survival of each primitive (chapter 8's labels), and $(\mu, \log s)$ start at the prior
#   and minimise, with the reparameterisation trick, the expected training loss plus
#   $\mathrm{KL}(P\|P_0)/N$: a heuristic, differentiable surrogate of the bound (a training loss in
#   place of the 0/1 cost, plus the bound's price for moving away from the prior).
#
# Then every training world is run with its own draws from $P$, and every held-out world with one.
# All of it is one artifact, built by `python -m husky_course train certificate` (part of
# `train all`); the cell below loads it.

# %%
result = get_certificate(profile)
cert, post = result.certificate, result.posterior
shift = (post.mean - post.prior_mean) / post.prior_std
fig, axes = plt.subplots(1, 3, figsize=(11, 3))
axes[0].plot(np.arange(1, len(post.losses) + 1), post.losses, "o-", ms=3)
axes[0].set_xlabel("epoch")
axes[0].set_ylabel("E[BCE] + KL / N")
axes[0].set_title("fitting the posterior", fontsize=9)
axes[1].hist(shift, bins=40, color="tab:blue")
axes[1].set_xlabel("(mu - w0) / s0")
axes[1].set_title("how far each mean moved, in prior deviations", fontsize=9)
axes[2].hist(post.std / post.prior_std, bins=40, color="tab:purple")
axes[2].set_xlabel("s / s0")
axes[2].set_title("posterior deviation / prior deviation", fontsize=9)
plt.tight_layout()
plt.show()
display(Markdown(
    f"The output layer has {post.mean.size} weights; the prior's deviation is {post.prior_std:.4f}. The "
    f"fitted posterior moved its means by {np.sqrt(np.mean(shift ** 2)):.2f} prior deviations (RMS) and "
    f"its deviations to {np.mean(post.std / post.prior_std):.2f} of the prior's on average: "
    f"KL(P || P0) = {cert.kl:.2f} nats, which the bound divides by N = {cert.n_worlds}."))

# %% [markdown]
# ## The certificate, and the held-out worlds that test it
#
# In the lab's format: the bound computed from the training worlds, beside the cost measured on
# held-out worlds, and beside the Clopper–Pearson bound those held-out worlds give at the same
# confidence (the test-set bound of chapter 7). One more row is free: the posterior was fitted on
# the first `finetune_worlds` training worlds only, so the others are, for it, held-out worlds in
# all but name, and give a Clopper–Pearson bound of their own without spending a single new world.

# %%
lo, hi = result.heldout_ci95
rows = [
    {"quantity": f"training cost, sampled (N = {cert.n_worlds} worlds, {g.draws_per_world} draw(s) each)",
     "value": f"{cert.sampled_cost:.3f}"},
    {"quantity": f"sample-convergence bound on the training cost (delta' = {cert.delta_prime})",
     "value": f"{cert.train_cost_bound:.3f}"},
    {"quantity": "KL(P || P0), nats", "value": f"{cert.kl:.2f}"},
    {"quantity": f"**PAC-Bayes certificate**, {cert.confidence:.0%} confidence, from the training worlds",
     "value": f"**{cert.bound:.3f}**"},
    {"quantity": f"cost measured on {result.heldout_costs.size} held-out worlds [exact 95% CI]",
     "value": f"{result.heldout_cost:.3f} [{lo:.3f}, {hi:.3f}]"},
    {"quantity": f"Clopper–Pearson bound from those held-out worlds, {cert.confidence:.0%} confidence",
     "value": f"{result.test_bound:.3f}"},
    {"quantity": f"Clopper–Pearson bound from the {result.unfitted_costs.size} training worlds the posterior "
                 f"was not fitted on, {cert.confidence:.0%} confidence",
     "value": f"{result.unfitted_bound:.3f}"},
]
display(Markdown(markdown_table(rows)))

# %%
pts = lambda x: f"{100 * abs(x):.1f} points"  # noqa: E731 (a distance between two rates)
if cert.bound >= hi:
    verdict = (f"The held-out worlds agree with it: the bound lies above their whole 95% interval, "
               f"{pts(cert.bound - result.heldout_cost)} above the measured cost. ")
elif cert.bound >= lo:
    verdict = "The held-out worlds cannot tell whether it holds: the bound lies inside their 95% interval. "
else:
    verdict = (f"**The held-out worlds are evidence that it fails** (which it may, with probability at most "
               f"{g.delta + g.delta_prime:.0%}): the bound lies {pts(lo - cert.bound)} below their 95% interval. ")
bounds = sorted([("the certificate", cert.bound),
                 ("the held-out worlds' Clopper–Pearson bound", result.test_bound),
                 ("the unfitted training worlds' Clopper–Pearson bound", result.unfitted_bound)],
                key=lambda t: t[1])
display(Markdown(
    f"The certificate says the stochastic student's expected failure rate, over worlds of this "
    f"distribution and its own weight draws, is at most **{cert.bound:.1%}** ({cert.confidence:.0%} "
    f"confidence); on {result.heldout_costs.size} worlds it never saw it failed in "
    f"**{result.heldout_cost:.1%}** (95% interval {lo:.1%} to {hi:.1%}). " + verdict
    + f"The bound is the sampled training cost ({cert.sampled_cost:.1%}), plus "
    f"{pts(cert.train_cost_bound - cert.sampled_cost)} for sample convergence, plus "
    f"{pts(cert.bound - cert.train_cost_bound)} for the PAC-Bayes term (the KL and the confidence, over N "
    f"worlds). Of the three bounds at {cert.confidence:.0%} confidence, the tightest is {bounds[0][0]} "
    f"({bounds[0][1]:.1%}) and the loosest {bounds[-1][0]} ({bounds[-1][1]:.1%}). The held-out bound "
    f"spent {result.heldout_costs.size} worlds that nothing was fitted on; the certificate spent none beyond "
    "the training worlds, and unlike the unfitted-worlds bound it would still hold had the posterior been "
    "fitted on all of them."))

# %%
fig, ax = plt.subplots(figsize=(7.5, 3.2))
steps = [("sampled\ntraining cost", cert.sampled_cost, "0.6"),
         ("+ sample\nconvergence", cert.train_cost_bound, "tab:orange"),
         ("+ PAC-Bayes term\n(the certificate)", cert.bound, "tab:red")]
for i, (_, value, color) in enumerate(steps):
    ax.bar(i, value, color=color)
    ax.text(i, value + 0.005, f"{value:.3f}", ha="center", fontsize=8)
ax.errorbar(3, result.heldout_cost, yerr=[[result.heldout_cost - lo], [hi - result.heldout_cost]],
            fmt="o", color="tab:green", capsize=5)
ax.text(3, hi + 0.005, f"{result.heldout_cost:.3f}", ha="center", fontsize=8)
for i, value in ((4, result.test_bound), (5, result.unfitted_bound)):
    ax.bar(i, value, color="tab:cyan")
    ax.text(i, value + 0.005, f"{value:.3f}", ha="center", fontsize=8)
labels = [s[0] for s in steps] + [f"held-out cost\n({result.heldout_costs.size} worlds)",
                                  "Clopper–Pearson\n(held-out)", "Clopper–Pearson\n(unfitted)"]
ax.set_xticks(range(6), labels, fontsize=7)
ax.set_ylabel("cost (did not cross)")
ax.set_title("From the training cost to the certificate, and the test-set checks", fontsize=9)
plt.tight_layout()
plt.show()

# %% [markdown]
# ## How many worlds
#
# The certificate gets tighter with more training worlds. The curve below recomputes it from the
# first $n$ training worlds' measured costs (the same posterior and KL), beside the Clopper–Pearson
# bound from the first $n$ held-out worlds; each point is a valid bound on its own (not all points
# at once). Both approach the policy's cost, estimated by the dashed line; either falls below it
# only with probability at most $\delta + \delta'$. Their slack shrinks like $\log(n)/n$ when the
# cost is near zero and like $\sqrt{\log(n)/n}$ otherwise.

# %%
ns = np.unique(np.geomspace(50, cert.n_worlds, 25).astype(int))
pb = [certificate(result.train_costs[:, :n], cert.kl, cert.delta, cert.delta_prime, draws="per_world").bound
      for n in ns]
hs = np.unique(np.geomspace(50, result.heldout_costs.size, 25).astype(int))
cp = [clopper_pearson(int(result.heldout_costs[:n].sum()), int(n), cert.confidence, "upper")[1] for n in hs]
fig, ax = plt.subplots(figsize=(6.5, 3.3))
ax.plot(ns, pb, "o-", ms=3, color="tab:red", label="PAC-Bayes certificate (first n training worlds)")
ax.plot(hs, cp, "s-", ms=3, color="tab:cyan", label="Clopper–Pearson (first n held-out worlds)")
ax.axhline(result.heldout_cost, color="tab:green", ls="--", lw=1,
           label=f"measured on {result.heldout_costs.size} held-out worlds")
ax.set_xscale("log")
ax.set_xlabel("n worlds")
ax.set_ylabel(f"bound on the cost ({cert.confidence:.0%})")
ax.legend(fontsize=7)
plt.show()
quarter = certificate(result.train_costs[:, : cert.n_worlds // 4], cert.kl, cert.delta, cert.delta_prime,
                      draws="per_world")
slack, slack_quarter = cert.bound - cert.sampled_cost, quarter.bound - quarter.sampled_cost


def where(bound):
    side = "above" if bound >= result.heldout_cost else "below"
    return f"{100 * abs(bound - result.heldout_cost):.1f} points {side}"


display(Markdown(
    f"With all {cert.n_worlds} training worlds the certificate lies {where(cert.bound)} the measured cost; "
    f"the Clopper–Pearson bound from all {result.heldout_costs.size} held-out worlds lies "
    f"{where(result.test_bound)} it. With the first {cert.n_worlds // 4} training worlds the certificate's "
    f"slack over its own sampled cost would be {slack_quarter / slack:.1f} times what it is with all of them: "
    "tightening a certificate is bought with worlds, and every world is an independent task, which is where "
    "more than one machine helps (`--engine ray`; the README's section on Ray says how to attach to a "
    "cluster)."))

# %% [markdown]
# ## Exercises
#
# 1. *Inverting kl.* Write your own bisection for the largest $p$ with $\mathrm{kl}(0.1\|p) \le 0.02$
#    (use `bernoulli_kl`), then check it with `exercises.check_kl_inverse(0.1, 0.02, your_p)`.
# 2. *Sizing a certificate.* A posterior with training cost 0.2 and KL 20 nats: what is the fewest
#    number of worlds $N$ for which the PAC-Bayes-kl bound (`pac_bayes_kl_bound`, $\delta$ = 0.009)
#    is at most 0.25? Check with `exercises.check_worlds_for_pac_bayes(0.2, 20, 0.25, your_n, 0.009)`.
# 3. The posterior's deviation `s` multiplies a random draw for every weight. What happens to the
#    KL term, and to the stochastic policy's cost, if the prior's `prior_scale` is halved? Which of
#    the two would you expect to dominate the certificate? (Try it with another collection seed for
#    the training worlds and evaluation set 1, never on the worlds above; and remember that a setting
#    chosen as the best of several must share $\delta$ among them.)
# 4. Why may the posterior be fitted on the certificate's own training worlds, while the prior may
#    not? What would go wrong if $w_0$ came from a network trained on those worlds?
