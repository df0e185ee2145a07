"""Draw the book's pipeline figure (the paper's Figure 1) as ``pipeline.svg`` next to this file.

Run from anywhere: ``python book/figures/draw_pipeline.py``. The output is committed, so the book
builds without running this; the same script gives the same bytes (no date, fixed SVG ids).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

#: (title, details, chapters) of each stage, left to right
STAGES = [
    ("PyBullet course", "10 × 10 m, 20 cylinders\nHusky, 50 × 50 depth camera\n25 motion primitives",
     "ch. 1"),
    ("Random-policy videos", "up to 10 primitives each\nimage, primitive, safety label\n(−1 at a collision)",
     "ch. 2"),
    ("Encoder + Decoder", "image t + primitive\n→ image t + 1\n(15-number latent)", "ch. 3"),
    ("Reward Net", "latent → P(collision)\nfails on a frozen latent;\ntrained jointly", "ch. 4, 5"),
    ("Look-ahead planner", "Algorithm 1: score every\nprimitive several steps\nahead, apply the best",
     "ch. 6, 7"),
]
WIDTH, HEIGHT, GAP = 2.3, 1.55, 0.55
COLOURS = ["#dbe9f6", "#dbe9f6", "#fde7c8", "#fde7c8", "#d9f0d3"]


def draw(out: Path) -> None:
    """Draw the figure and save it as SVG to ``out``."""
    plt.rcParams["svg.hashsalt"] = "husky-pipeline"
    n = len(STAGES)
    fig, ax = plt.subplots(figsize=(12.5, 3.6))
    for k, ((title, details, chapters), colour) in enumerate(zip(STAGES, COLOURS, strict=True)):
        x = k * (WIDTH + GAP)
        ax.add_patch(FancyBboxPatch((x, 0), WIDTH, HEIGHT, boxstyle="round,pad=0.02,rounding_size=0.12",
                                    fc=colour, ec="0.3", lw=1.2))
        ax.text(x + WIDTH / 2, HEIGHT - 0.22, title, ha="center", va="center", fontsize=11, weight="bold")
        ax.text(x + WIDTH / 2, HEIGHT / 2 - 0.12, details, ha="center", va="center", fontsize=8.5,
                linespacing=1.35)
        ax.text(x + WIDTH / 2, -0.2, chapters, ha="center", va="center", fontsize=9, color="0.35")
        if k < n - 1:
            start, end = (x + WIDTH + 0.04, HEIGHT / 2), (x + WIDTH + GAP - 0.04, HEIGHT / 2)
            arrow = FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=16, lw=1.5, color="0.2")
            ax.add_patch(arrow)
    right = n * WIDTH + (n - 1) * GAP
    ax.add_patch(FancyArrowPatch((right - WIDTH / 2, HEIGHT + 0.04), (WIDTH / 2, HEIGHT + 0.04),
                                 connectionstyle="arc3,rad=0.12", arrowstyle="-|>", mutation_scale=14,
                                 lw=1.2, ls="--", color="tab:green"))
    loop = "the planner applies its primitive in the simulator, which renders the next image"
    ax.text(right / 2, HEIGHT + 0.92, loop, ha="center", va="center", fontsize=9, color="tab:green")
    videos, reward = (WIDTH + GAP + WIDTH / 2, -0.36), (3 * (WIDTH + GAP) + WIDTH / 2, -0.36)
    ax.add_patch(FancyArrowPatch(videos, reward, connectionstyle="arc3,rad=0.1", arrowstyle="-|>",
                                 mutation_scale=14, lw=1.2, ls=":", color="tab:orange"))
    ax.text(2 * (WIDTH + GAP) + WIDTH / 2, -0.78, "the safety labels train the reward net (the reward set)",
            ha="center", va="center", fontsize=9, color="tab:orange")
    ax.set_xlim(-0.1, right + 0.1)
    ax.set_ylim(-1.0, HEIGHT + 1.1)
    ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(out, format="svg", metadata={"Date": None})
    plt.close(fig)


if __name__ == "__main__":
    draw(Path(__file__).resolve().with_name("pipeline.svg"))
