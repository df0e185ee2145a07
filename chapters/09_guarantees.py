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
# The paper's data came from "a policy based on PAC-Bayes framework" (its abstract), the framework of its lab. The lab's own
# vision-based planners (the same 50×50 depth images, 25 primitives and 20 cylinders, on a
# quadrotor) report a bound computed from training environments alone and compare it with the cost
# measured on new ones. Until now this course offered only the second kind of statement: a
# Clopper–Pearson bound from held-out worlds (chapters 7 and 8). A held-out bound needs worlds the
# planner was never tuned on, set aside and spent; a PAC-Bayes certificate is computed from the
# very worlds the policy was fitted on.

# %%
import matplotlib.pyplot as plt
import numpy as np
from IPython.display import Markdown, display

from husky_course.config import get_profile
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
# worlds, giving $L$ independent averages. We draw a *fresh* vector for every world instead: then
# all $N$ costs are independent given the worlds, each in $[0, 1]$, and their mean has expectation
# $C_S(P)$. Hoeffding's inequality in its kl form holds for independent variables that need not be
# identically distributed, so with probability at least $1-\delta'$,
# $C_S(P) \le \mathrm{kl}^{-1}\big(\hat C_S, \log(2/\delta')/N\big)$ (we keep the lab's two-sided
# constant). Together: $C(P)$ is bounded with probability at least $1-\delta-\delta'$.
#
# The choices, and why. $\delta = 0.009$ and $\delta' = 0.001$, the lab's values: 99% confidence
# overall. $N$ (printed above) is sized so that both terms of the bound cost a few points and the
# whole certificate builds within the book's time budget; the section "How many worlds" below shows
# what a larger $N$ would buy. The certificate's training worlds come from a collection seed that no
# dataset, calibration or DAgger round uses; the held-out worlds are evaluation set 2 (set 0 is the
# reporting set of chapters 7 and 8, set 1 their tuning set).

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
#   before any certificate world is seen, which is all the bound asks of a prior ("weights trained on
#   a separate split").
# - **Posterior** $P = \mathcal N(\mu, \mathrm{diag}(s^2))$, fitted on $S$: the student drives in the
#   first `finetune_worlds` of the training worlds, every state it visits is labelled with the
#   simulator's survival of each primitive (chapter 8's labels), and $(\mu, \log s)$ start at the prior
#   and minimise, with the reparameterisation trick, the expected training loss plus
#   $\mathrm{KL}(P\|P_0)/N$: a differentiable stand-in for the bound itself.
#
# Then every training world is run once with its own draw from $P$, and every held-out world too.
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
# In the lab's format: the bound computed from the training worlds alone, beside the cost measured
# on held-out worlds, and beside the Clopper–Pearson bound those held-out worlds give at the same
# confidence (the test-set bound of chapter 7).

# %%
lo, hi = result.heldout_ci95
rows = [
    {"quantity": f"training cost, sampled (N = {cert.n_worlds} worlds, one draw each)",
     "value": f"{cert.sampled_cost:.3f}"},
    {"quantity": f"sample-convergence bound on the training cost (delta' = {cert.delta_prime})",
     "value": f"{cert.train_cost_bound:.3f}"},
    {"quantity": "KL(P || P0), nats", "value": f"{cert.kl:.2f}"},
    {"quantity": f"**PAC-Bayes certificate**, {cert.confidence:.0%} confidence, from training worlds alone",
     "value": f"**{cert.bound:.3f}**"},
    {"quantity": f"cost measured on {result.heldout_costs.size} held-out worlds [exact 95% CI]",
     "value": f"{result.heldout_cost:.3f} [{lo:.3f}, {hi:.3f}]"},
    {"quantity": f"Clopper–Pearson bound from the held-out worlds, {cert.confidence:.0%} confidence",
     "value": f"{result.test_bound:.3f}"},
]
display(Markdown(markdown_table(rows)))

# %%
holds = cert.bound >= result.heldout_cost
covers_interval = cert.bound >= hi
pts = lambda x: f"{100 * x:.1f} points"  # noqa: E731 (a difference of two rates)
display(Markdown(
    f"The certificate says the stochastic student fails to cross at most **{cert.bound:.1%}** of the "
    f"worlds of this distribution ({cert.confidence:.0%} confidence); on {result.heldout_costs.size} worlds "
    f"it never saw it failed in **{result.heldout_cost:.1%}** (95% interval {lo:.1%} to {hi:.1%}). "
    + (f"The bound holds, {pts(cert.bound - result.heldout_cost)} above the measured cost"
       + (" and above the whole interval. " if covers_interval else ", though inside the interval's reach. ")
       if holds else
       f"**The bound does not hold**: the measured cost exceeds it by {pts(result.heldout_cost - cert.bound)}. ")
    + f"It is built as the sampled training cost ({cert.sampled_cost:.1%}), plus "
    f"{pts(cert.train_cost_bound - cert.sampled_cost)} for sample convergence (the training cost estimated "
    f"from one draw per world), plus {pts(cert.bound - cert.train_cost_bound)} for the PAC-Bayes term (the KL "
    f"and the confidence, over N worlds); the held-out cost differs from the training cost by "
    f"{pts(result.heldout_cost - cert.sampled_cost)}. "
    f"The held-out worlds themselves certify {result.test_bound:.1%} at the same confidence, "
    + ("tighter, " if result.test_bound < cert.bound else "looser, ")
    + f"but only by spending {result.heldout_costs.size} worlds that nothing was fitted on."))

# %%
fig, ax = plt.subplots(figsize=(7, 3.2))
steps = [("sampled\ntraining cost", cert.sampled_cost, "0.6"),
         ("+ sample\nconvergence", cert.train_cost_bound, "tab:orange"),
         ("+ PAC-Bayes term\n(the certificate)", cert.bound, "tab:red")]
for i, (_, value, color) in enumerate(steps):
    ax.bar(i, value, color=color)
    ax.text(i, value + 0.005, f"{value:.3f}", ha="center", fontsize=8)
ax.errorbar(3, result.heldout_cost, yerr=[[result.heldout_cost - lo], [hi - result.heldout_cost]],
            fmt="o", color="tab:green", capsize=5)
ax.text(3, hi + 0.005, f"{result.heldout_cost:.3f}", ha="center", fontsize=8)
ax.bar(4, result.test_bound, color="tab:cyan")
ax.text(4, result.test_bound + 0.005, f"{result.test_bound:.3f}", ha="center", fontsize=8)
ax.set_xticks(range(5), [s[0] for s in steps] + [f"held-out cost\n({result.heldout_costs.size} worlds)",
                                                 "Clopper–Pearson\n(held-out)"], fontsize=8)
ax.set_ylabel("cost (did not cross)")
ax.set_title("From the training cost to the certificate, and the held-out check", fontsize=9)
plt.tight_layout()
plt.show()

# %% [markdown]
# ## How many worlds
#
# The certificate gets tighter with more training worlds: both terms shrink roughly like
# $\sqrt{\log(\cdot)/N}$. The curve below recomputes it from the first $n$ of the training worlds'
# measured costs (the same posterior and KL), beside the Clopper–Pearson bound from the first $n$
# held-out worlds. The stochastic policy's own cost is the floor neither bound can go below.

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
                      draws="per_world").bound
slack, slack_quarter = cert.bound - cert.sampled_cost, quarter - cert.sampled_cost
display(Markdown(
    f"With all {cert.n_worlds} training worlds the certificate sits {100 * (pb[-1] - result.heldout_cost):.1f} "
    f"points above the measured cost; the Clopper–Pearson bound from all {result.heldout_costs.size} held-out "
    f"worlds sits {100 * (cp[-1] - result.heldout_cost):.1f} points above it. With a quarter of the training "
    f"worlds the certificate's slack over the training cost would be {slack_quarter / slack:.1f} times what "
    "it is: tightening a certificate is bought with worlds, and every world is an independent task, which is "
    "where more than one machine helps (`--engine ray`; the README's section on Ray says how to attach to a "
    "cluster)."))
