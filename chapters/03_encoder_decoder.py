# %% [markdown]
# # 3. Predicting the next depth image: the encoder and the decoder
#
# **Learning objectives.** After this chapter you can
#
# - build the paper's encoder (depth image → 15 numbers) and decoder (15 numbers + a primitive →
#   the next depth image) in PyTorch and count their parameters;
# - train them with the course's trainer (Adam, early stopping, checkpoints, TensorBoard) and read
#   the training and validation curves (the paper's Graph 1);
# - test the model on worlds it never saw (the paper's Figure 8) and measure the paper's own
#   observation: obstacles land in the right *place* but at the wrong *distance*.
#
# The pipeline (paper Fig. 3) sees the depth image at time *t* and the primitive about to be applied
# and must draw the depth image at *t + 1*. Its training pairs are the collision-free steps of the
# random-policy videos from chapter 2 (an image taken just before a collision has no successor).

# %%
import matplotlib.pyplot as plt
import numpy as np
import torch
from IPython.display import Markdown, display

from husky_course.config import get_profile
from husky_course.course import exercises  # noqa: F401  (used in the exercises)
from husky_course.data.collect import fresh_pairs
from husky_course.data.splits import encoder_decoder_pairs
from husky_course.data.store import get_dataset
from husky_course.evaluation.metrics import OCCUPIED_BELOW, image_errors
from husky_course.models.base import count_parameters
from husky_course.models.paper import EncoderDecoder
from husky_course.sim.camera import horizon_rows
from husky_course.training import builders, inference
from husky_course.ui import plotting

profile = get_profile()
ds = get_dataset(profile)
print("profile:", profile.name, "| images in the pool:", len(ds))

# %% [markdown]
# ## The architecture, and what the paper left open
#
# The paper fixes the encoder's layers (BatchNorm → Conv(1→32, 10×10, stride 2) → ELU →
# Conv(32→16, 8×8, stride 2) → ELU → fully connected → 15), the decoder's input size (16) and its
# output (2,500 values through a sigmoid). Where it is silent we chose, and say so:
#
# | question the paper leaves open | our choice | why |
# |---|---|---|
# | how the primitive enters the decoder | one number: its lateral offset scaled to [−1, 1] | the input of 16 = 15 + 1 leaves room for one number; neighbouring primitives get neighbouring inputs |
# | layers after the convolutions | one fully connected layer (784 → 15) | Fig. 5 shows the flattened volume followed directly by the latent |
# | decoder widths | fully connected layers widening from 16 to 2,500 (each width is in the model printed below) | "fully connected layers of growing width" |
# | train/validation split | 80/20 **by video** | consecutive frames are near-duplicates; a split by image would validate on pictures the model has nearly seen |
# | sigmoid + BCE | the loss is computed on the pre-sigmoid values (`binary_cross_entropy_with_logits`) | the same loss, without overflow |

# %%
# NBVAL_CHECK_OUTPUT
torch.manual_seed(0)
model = EncoderDecoder()
print(model)
print(f"encoder parameters: {count_parameters(model.encoder):,}")
print(f"decoder parameters: {count_parameters(model.decoder):,}")

# %% [markdown]
# The 50 × 50 image shrinks to 21 × 21 after the first convolution and to 7 × 7 after the second,
# so the fully connected layer sees 16 × 7 × 7 = 784 numbers. The counts above show where the size
# is: in the decoder, whose last layer must paint 2,500 pixels.
#
# ## Training on a laptop CPU
#
# The paper trained with Adam at a learning rate of 1e-5 and batch 32 for 3,200 epochs (about
# 12 hours). We choose our own learning rate and batch size and stop early on the validation loss;
# the table below compares the settings with the paper's, with the epochs and wall time this run
# actually took. Two tricks make the CPU fast: images are laid out `channels_last` for the convolutions, and Adam runs its `fused`
# implementation.
#
# The first call trains and saves a checkpoint under `artifacts/<profile>/models/`; every later call
# (and every later chapter) loads it. A TensorBoard log of the run goes to `runs/`
# (`tensorboard --logdir runs`), as the paper monitored its training.

# %%
split = encoder_decoder_pairs(ds, seed=profile.data.seed)
cfg = profile.train.encoder_decoder
ed = builders.get_encoder_decoder(profile)
hist = ed.history

stop = f"stopped early, cap {cfg.epochs}" if hist.stopped_early else f"the cap of {cfg.epochs}: no early stop"
rows = [("learning rate", "1e-5", cfg.lr), ("batch size", 32, cfg.batch_size),
        ("epochs", "3,200 (stopped by hand)", f"{len(hist.train_loss)} ({stop})"),
        ("wall time", "~12 h", f"{hist.seconds:.0f} s"),
        ("training pairs", "80% of safe images", len(split.train_t)),
        ("validation pairs", "20%", len(split.val_t))]
display(Markdown(plotting.markdown_table(rows, header=["setting", "paper", "this run"])))

# %%
fig, ax = plt.subplots(figsize=(6, 3.5))
plotting.plot_curves(hist, ax, "Encoder + decoder: per-pixel BCE (the paper's Graph 1)")
plt.show()

tl, vl = np.array(hist.train_loss), np.array(hist.val_loss)
k = min(3, len(vl) - 1)  # the last k epochs
target = np.clip(ds.images[split.val_t + 1].astype(np.float64), 1e-6, 1 - 1e-6)
floor = float(-(target * np.log(target) + (1 - target) * np.log(1 - target)).mean())
gap = (vl[-1] - tl[-1]) / tl[-1]
text = [f"Training loss {tl[0]:.4f} → {tl[-1]:.4f}, validation loss {vl[0]:.4f} → {vl[-1]:.4f} "
        "(first to last epoch)."]
if tl[-1] < tl[0] and vl[-1] < vl[0]:
    late = (vl[-1 - k] - vl[-1]) / (vl[0] - vl[-1])  # share of the validation loss's fall
    text.append(f"Both curves fall, and the last {k} epochs gave {late:.0%} of the validation loss's fall: "
                + ("they have levelled off." if late < 0.15 else "they are still falling."))
else:
    text.append("The curves do not both fall.")
if abs(gap) < 0.05:
    text.append(f"The validation loss ends within {abs(gap):.1%} of the training loss, so the model is not "
                "memorising its training videos.")
else:
    text.append(f"The validation loss ends {gap:+.1%} from the training loss"
                + (": the model fits its training videos better than new ones." if gap > 0 else "."))
text.append("Neither can reach zero: even a perfect prediction keeps the BCE of the targets' own grey "
            f"levels, {floor:.4f} on these validation targets; the last validation loss is "
            f"{vl[-1] - floor:.4f} above it.")
display(Markdown(" ".join(text)))

# %% [markdown]
# ## The visual test on new worlds (the paper's Figure 8)
#
# The paper generated a fresh dataset of 20 images and compared, side by side, the image at *t*, the
# true image at *t + 1* and the prediction. We do the same on 20 worlds generated from a seed that no
# training video used.

# %%
fresh = fresh_pairs(20, seed=profile.course.fresh_pairs_seed, config=profile.sim)
pred_fresh = inference.predict_next(ed.model, fresh["image"], fresh["prim"])
fig = plotting.prediction_grid(fresh["image"], fresh["next"], pred_fresh)
plt.show()

# %% [markdown]
# ## Right place, wrong distance: the paper's observation measured
#
# The paper saw that predicted obstacles sit in the right *x–y place* of the image but often have the
# wrong colour, i.e. the wrong *distance*. We split the error the same way, on the horizon rows of
# the image (where a level camera sees vertical surfaces and never the ground):
#
# - **column IoU**: do the predicted and the true image have a surface nearer than a fixed
#   distance (`metrics.OCCUPIED_BELOW` of the depth range, printed below) in the same columns?
#   (1 = the obstacles are exactly where they should be);
# - **depth error (m)**: in the columns where both images have such a surface, how far off is its
#   distance?
#
# A simple reference makes the numbers meaningful: *copy*, which predicts that the next image equals
# the current one.

# %%
val_t = split.val_t
pred_val = inference.predict_next(ed.model, ds.images[val_t], ds.applied[val_t])
true_val = ds.images[val_t + 1].astype(np.float32)
copy_val = ds.images[val_t].astype(np.float32)
table = {
    "model, validation pairs": image_errors(pred_val, true_val),
    "copy, validation pairs": image_errors(copy_val, true_val),
    "model, 20 new worlds": image_errors(pred_fresh, fresh["next"]),
    "copy, 20 new worlds": image_errors(fresh["image"], fresh["next"]),
}
display(Markdown(plotting.markdown_table([{"": k, **v.row()} for k, v in table.items()])))
m, c = table["model, validation pairs"], table["copy, validation pairs"]
cam = profile.sim.camera
span = cam.far - cam.near
place = (m.column_iou - c.column_iou) / (1 - c.column_iou)  # share of copy's IoU shortfall closed
distance = (c.depth_error_m - m.depth_error_m) / c.depth_error_m  # share of copy's depth error removed
display(Markdown(
    f"A column counts as occupied when its surface is nearer than {cam.near + OCCUPIED_BELOW * span:.2f} m. "
    f"On the validation pairs the model's column IoU is **{m.column_iou:.2f}** (copy: {c.column_iou:.2f}) "
    f"while its depth error is **{m.depth_error_m:.2f} m** (copy: {c.depth_error_m:.2f} m), "
    f"{m.depth_error_m / span:.0%} of the camera's {span:.2f} m depth range. Against copying, the model "
    f"closes {place:.0%} of the gap to a perfect column IoU but removes {distance:.0%} of the depth error: "
    + ("it has learned where obstacles are much better than how far away they are, which is the paper's "
       "observation in numbers." if place > 2 * distance else
       "here it improves the distance about as much as the place, unlike the paper's observation.")))

# %%
# the nearest surface's distance (m) in the horizon rows, predicted vs true
rows = horizon_rows(cam)
near_true = cam.near + true_val[:, rows].mean(1).min(1) * span
near_pred = cam.near + pred_val[:, rows].mean(1).min(1) * span
fig, ax = plt.subplots(figsize=(4, 4))
ax.plot(near_true, near_pred, ".", ms=2, alpha=0.4)
ax.plot([0, cam.far], [0, cam.far], "k--", lw=1)
ax.set_xlabel("true distance of the nearest surface (m)")
ax.set_ylabel("predicted (m)")
ax.set_title("Nearest surface at t+1, validation pairs", fontsize=10)
plt.show()

# %% [markdown]
# ## Exercises
#
# 1. Retrain with the paper's learning rate (`dataclasses.replace(cfg, lr=1e-5)` in a custom call to
#    `husky_course.training.fit`). How many epochs does it take to reach the loss our run reached?
#    What does that say about the paper's 12 hours?
# 2. Encode the primitive as a one-hot vector of 25 instead of one number (the decoder's input
#    becomes 40). Does the validation loss improve? Why might one number be enough here?
# 3. Which pixels does the decoder get most wrong? Average `|pred - true|` over the validation set
#    and show it as an image. Explain the pattern using the camera geometry of chapter 1.
# 4. *Sizes through the encoder.* With a 64 × 64 camera, how many numbers would the encoder's fully
#    connected layer receive? Work it out with `(side − kernel) // stride + 1` per convolution, then
#    check with `exercises.check_encoder_features(64, your_n)`.
