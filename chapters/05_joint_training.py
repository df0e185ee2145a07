# %% [markdown]
# # 5. The fix: training encoder, decoder and safety together
#
# **Learning objectives.** After this chapter you can
#
# - build the joint model the paper proposed (Fig. 9) and train it on a total loss;
# - condition a safety prediction on the primitive by predicting all 25 at once;
# - check a probabilistic classifier with ROC AUC, accuracy and a reliability diagram;
# - compare it fairly with the paper's reward net and chapter 4's variants on the same validation set.
#
# The paper's remedy: instead of freezing an encoder trained only to predict images, train the
# encoder, the decoder and the reward net *together*, on reconstruction loss + safety loss, so the
# latent has to keep what safety needs. Chapter 4 adds a second lesson: the label depends on the
# primitive. Our safety head therefore maps the latent to **25 collision probabilities**, one per
# primitive, and is trained on the one that was applied. A planner then gets all 25 from one pass.

# %%
import matplotlib.pyplot as plt
import numpy as np
import torch
from IPython.display import Markdown, display

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.data import splits
from husky_course.data.labels import primitive_outcomes
from husky_course.data.splits import encoder_decoder_pairs, reward_set
from husky_course.data.store import get_dataset
from husky_course.evaluation.metrics import classification, image_errors, reliability, roc_auc
from husky_course.models.base import count_parameters
from husky_course.models.safety import JointModel
from husky_course.training import builders, datasets, inference
from husky_course.ui import plotting
from husky_course.ui.plotting import markdown_table

profile = get_profile()
ds = get_dataset(profile)

# %%
# NBVAL_CHECK_OUTPUT
torch.manual_seed(0)
joint = JointModel()
print("safety head:", joint.safety)
for part in ("encoder", "decoder", "safety"):
    print(f"{part:8s} {count_parameters(getattr(joint, part)):>9,} parameters")

# %% [markdown]
# ## The total loss
#
# For every image of the training videos: the safety BCE of the applied primitive's probability
# against the recorded label, and, where the step was safe (so a next image exists), the per-pixel
# reconstruction BCE of chapter 3. Total = reconstruction + `safety_weight` × safety (the weight is
# printed below).
# Unlike the paper's second pipeline, the colliding frames are now part of the encoder's training.

# %%
j = builders.get_joint(profile)
fig, ax = plt.subplots(figsize=(6, 3.5))
plotting.plot_curves(j.history, ax, "Joint model: reconstruction + safety BCE", "total loss")
plt.show()
print(f"safety_weight {j.model.safety_weight}; trained for {len(j.history.train_loss)} epochs "
      f"in {j.history.seconds:.0f} s")

# %% [markdown]
# ## Does it predict collisions?
#
# We score the probability of the applied primitive on chapter 4's validation images (the same
# videos for every model), and add a reliability diagram: among the images given, say, 0.3, does a
# collision follow about 30% of the time?

# %%
rs = reward_set(ds, seed=profile.data.seed)
probs_rs = inference.collision_probs(j.model, ds.images[rs.val])
p_joint = probs_rs[np.arange(len(rs.val)), ds.applied[rs.val]]
joint_q = classification(ds.labels[rs.val], p_joint)

ed, rn = builders.get_reward_net(profile)
latents = inference.encode(ed.model.encoder, ds.images[rs.val])
with torch.no_grad():
    p_paper = rn.model(torch.from_numpy(latents))[:, 0].numpy()
d = datasets.safety_data(ds, rs.val)
with torch.no_grad():
    p_img = torch.sigmoid(builders.get_safety_net(False, profile).model.logit(d["image"])).numpy()
    p_prim = torch.sigmoid(builders.get_safety_net(True, profile).model.logit(d["image"], d["prim"])).numpy()
y = ds.labels[rs.val]
rows = [{"model": name, **classification(y, p).row()} for name, p in [
    ("paper's reward net (frozen latent)", p_paper), ("ch. 4: CNN end to end, image only", p_img),
    ("ch. 4: CNN end to end, image + primitive", p_prim), ("joint model (this chapter)", p_joint)]]
display(Markdown(markdown_table(rows)))

fig, ax = plt.subplots(figsize=(4.5, 4.5))
plotting.reliability_diagram(reliability(y, p_paper), ax, "paper's reward net")
plotting.reliability_diagram(reliability(y, p_joint), ax, "joint model")
ax.set_title("Reliability on the validation reward set", fontsize=10)
plt.show()

# %% [markdown]
# ## All 25 primitives, not only the applied one
#
# A planner compares the 25 probabilities of one image, but the dataset only ever labels one of
# them. The simulator can label all 25 (chapter 4), so we can ask the planner's real question: on
# validation images, does the model rank colliding primitives above safe ones?

# %%
tr_all, va_all = splits.split_all(ds, profile.data.seed)
truth = primitive_outcomes(ds, va_all, config=profile.sim)
probs_all = inference.collision_probs(j.model, ds.images[va_all])
auc_all = roc_auc(truth.ravel(), probs_all.ravel())
acc_all = float(((probs_all >= 0.5) == truth).mean())
display(Markdown(
    f"Over all 25 primitives of {len(va_all)} validation images ({truth.size:,} image–primitive pairs, "
    f"{truth.mean():.1%} colliding): ROC AUC **{auc_all:.3f}**, accuracy **{acc_all:.1%}** "
    f"(majority {max(truth.mean(), 1 - truth.mean()):.1%})."))

n_prims = profile.sim.primitives.n
i = va_all[int(np.argmax(truth.sum(1) * (truth.sum(1) < 20)))]  # an image with many but not all unsafe
k = int(np.flatnonzero(va_all == i)[0])
fig, axes = plt.subplots(1, 2, figsize=(9, 3), gridspec_kw={"width_ratios": [1, 3]})
plotting.show_depth(ds.image(i), axes[0], "the image")
axes[1].bar(range(n_prims), probs_all[k], color=np.where(truth[k], "tab:red", "tab:green"))
axes[1].set_xlabel(f"primitive (0 = far right, {n_prims - 1} = far left)")
axes[1].set_ylabel("predicted P(collision)")
axes[1].set_title("red: the simulator says it collides, green: safe", fontsize=9)
plt.show()

# %% [markdown]
# ## Did the images suffer?
#
# Adding the safety loss must not ruin the first pipeline's job. Same metric as chapter 3, same
# validation pairs.

# %%
split = encoder_decoder_pairs(ds, seed=profile.data.seed)
true_next = ds.images[split.val_t + 1].astype(np.float32)
models = [("encoder + decoder (ch. 3)", ed.model), ("joint model", j.model)]
rows = [{"model": name,
         **image_errors(inference.predict_next(m, ds.images[split.val_t], ds.applied[split.val_t]),
                        true_next, profile.sim.camera).row()} for name, m in models]
display(Markdown(markdown_table(rows)))
ch3, jm = rows
bce_change = jm["BCE"] / ch3["BCE"] - 1
kept = bce_change <= 0.05 and jm["column IoU"] >= ch3["column IoU"] - 0.05
display(Markdown(
    f"Reconstruction BCE {jm['BCE']:.3f} for the joint model against {ch3['BCE']:.3f} for chapter 3's "
    f"({bce_change:+.1%}), column IoU {jm['column IoU']:.3f} against {ch3['column IoU']:.3f}: the images are "
    + ("kept (within 5% in BCE and 0.05 in column IoU)" if kept else
       "somewhat worse (more than 5% in BCE or 0.05 in column IoU)")
    + f", while the safety prediction goes from AUC {classification(y, p_paper).auc:.3f} "
    f"to {joint_q.auc:.3f}."))

# %% [markdown]
# ## Exercises
#
# 1. Train the joint model with `safety_weight` 0.1 and 10 (`builders.get_joint(profile,
#    safety_weight=...)`). Plot AUC and reconstruction BCE against the weight. Is there a trade-off?
# 2. The safety head sees only the latent. Using the 25-primitive truth, find the primitives the
#    model ranks worst (lowest per-primitive AUC). Where are they in the library, and why?
# 3. Our joint model is trained on the applied primitive only. Write a loss that uses all 25
#    simulator labels per image. What does that assume about how the data was collected?
# 4. *ROC AUC by hand.* Compute the joint model's AUC on the validation reward set (`y` and `p_joint`
#    above) as the share of (colliding, safe) image pairs in which the colliding image gets the higher
#    probability, a tie counting one half. Check with `exercises.check_roc_auc(y, p_joint, your_auc)`.
