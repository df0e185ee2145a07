"""Figures and tables used by the chapters: top-down maps, depth images, the primitive library."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Rectangle

from ..sim.primitives import PrimitiveLibrary
from ..sim.world import World

DEPTH_CMAP = "viridis"  # perceptually uniform, as in the paper's Figure 2


MOVER_COLOUR = "tab:purple"  #: moving cylinders, in every figure


def draw_world(
    world: World, ax: Axes | None = None, robot_pose: np.ndarray | None = None, t: float = 0.0
) -> Axes:
    """Top-down map: walls, cylinders (at time ``t``; moving ones purple, with an arrow for one step
    of their motion), the course's start and finish lines, the robot's disc."""
    ax = ax or plt.gca()
    cfg = world.config
    half = world.wall_y
    for side in (-1, 1):
        y0 = half if side > 0 else -half - cfg.wall_thickness
        ax.add_patch(Rectangle((-1, y0), cfg.length + 2, cfg.wall_thickness, color="0.5"))
    movers = set(world.moving.tolist())
    now, soon = world.obstacles_at(t), world.obstacles_at(t + 1.0)
    for i, (x, y, r) in enumerate(now):
        ax.add_patch(Circle((x, y), r, color=MOVER_COLOUR if i in movers else "tab:orange"))
        if i in movers and abs(soon[i, 1] - y) > 1e-9:
            ax.annotate("", (x, soon[i, 1]), (x, y), arrowprops={"arrowstyle": "->", "color": MOVER_COLOUR})
    ax.axvline(0, color="0.7", ls=":", lw=1)
    ax.axvline(cfg.length, color="tab:green", ls="--", lw=1)
    pose = world.start if robot_pose is None else np.asarray(robot_pose)
    draw_robot(pose, cfg.robot_radius, ax)
    ax.set_xlim(-1, cfg.length + 1)
    ax.set_ylim(-half - 0.5, half + 0.5)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m), along the course")
    ax.set_ylabel("y (m)")
    return ax


def draw_robot(pose: np.ndarray, radius: float, ax: Axes, color: str = "tab:blue") -> None:
    """The robot's collision disc and heading arrow."""
    x, y, yaw = pose
    ax.add_patch(Circle((x, y), radius, fill=False, ec=color, lw=1.5))
    ax.arrow(x, y, 0.6 * np.cos(yaw), 0.6 * np.sin(yaw), head_width=0.15, color=color)


def draw_path(path: np.ndarray, ax: Axes, color: str = "tab:blue", **kw: object) -> None:
    """A played-back path ``(S, 3)`` (or several concatenated)."""
    ax.plot(path[:, 0], path[:, 1], color=color, **kw)


def show_depth(
    depth: np.ndarray, ax: Axes | None = None, title: str | None = None, colorbar: bool = False
) -> Axes:
    """A normalised depth image in viridis (0 = at the camera, 1 = nothing within ``far``)."""
    ax = ax or plt.gca()
    im = ax.imshow(depth, cmap=DEPTH_CMAP, vmin=0.0, vmax=1.0)
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)
    if colorbar:
        plt.colorbar(im, ax=ax, fraction=0.046, label="normalised depth")
    return ax


def draw_library(library: PrimitiveLibrary, radius: float, ax: Axes | None = None) -> Axes:
    """All primitives from the origin, with the robot's swept width for the two extremes."""
    ax = ax or plt.gca()
    colors = plt.cm.coolwarm(np.linspace(0, 1, library.n))
    for k in range(library.n):
        path = library.local_paths[k]
        ax.plot(path[:, 0], path[:, 1], color=colors[k], lw=1.2)
        ax.text(path[-1, 0] + 0.03, path[-1, 1], str(k), fontsize=6, va="center")
    for k in (0, library.n - 1):
        path = library.local_paths[k]
        for sign in (-1, 1):
            ax.plot(path[:, 0], path[:, 1] + sign * radius, color="0.6", lw=0.6, ls=":")
    draw_robot(np.zeros(3), radius, ax)
    ax.set_aspect("equal")
    ax.set_xlabel("forward (m)")
    ax.set_ylabel("left (m)")
    return ax


def figure_two(
    world: World, depth: np.ndarray, rgb: np.ndarray, pose: np.ndarray | None = None
) -> plt.Figure:
    """The paper's Figure 2, plus a map: RGB view, depth in viridis, top-down map."""
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), gridspec_kw={"width_ratios": [1, 1, 2.2]})
    axes[0].imshow(rgb)
    axes[0].set_axis_off()
    axes[0].set_title("onboard RGB", fontsize=9)
    show_depth(depth, axes[1], "onboard depth (viridis)", colorbar=True)
    draw_world(world, axes[2], pose)
    axes[2].set_title(f"world seed {world.seed}", fontsize=9)
    fig.tight_layout()
    return fig


def plot_curves(history: object, ax: Axes | None = None, title: str = "", ylabel: str = "BCE loss") -> Axes:
    """Training and validation loss per epoch (a :class:`~husky_course.training.History`)."""
    ax = ax or plt.gca()
    train, val = history.train_loss, history.val_loss  # type: ignore[attr-defined]
    epochs = np.arange(1, len(train) + 1)
    ax.plot(epochs, train, "o-", ms=3, label="training")
    ax.plot(epochs, val, "s-", ms=3, label="validation")
    best = history.best_epoch  # type: ignore[attr-defined]
    if best >= 0:
        ax.axvline(best + 1, color="0.6", ls=":", label=f"best (epoch {best + 1})")
    ax.set_xlabel("epoch")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    return ax


def prediction_grid(
    image: np.ndarray, true_next: np.ndarray, pred_next: np.ndarray, per_row: int = 4
) -> plt.Figure:
    """The paper's Figure 8: (image t | true t+1 | predicted t+1) triplets in viridis."""
    n = len(image)
    rows = int(np.ceil(n / per_row))
    fig, axes = plt.subplots(rows, 3 * per_row, figsize=(1.2 * 3 * per_row, 1.35 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for i in range(n):
        r, c = divmod(i, per_row)
        for j, (img, name) in enumerate(((image, "t"), (true_next, "true t+1"), (pred_next, "pred t+1"))):
            show_depth(img[i], axes[r, 3 * c + j], name if r == 0 else None)
    fig.tight_layout(pad=0.3)
    return fig


def reliability_diagram(bins: dict, ax: Axes | None = None, label: str = "") -> Axes:
    """Observed collision frequency against mean predicted probability per bin."""
    ax = ax or plt.gca()
    ok = bins["count"] > 0
    ax.plot([0, 1], [0, 1], color="0.6", ls="--", lw=1)
    ax.plot(bins["mean_p"][ok], bins["freq"][ok], "o-", label=f"{label} (ECE {float(bins['ece']):.3f})")
    ax.set_xlabel("predicted probability of collision")
    ax.set_ylabel("observed frequency of collision")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8)
    return ax


def markdown_table(
    rows: Sequence[Mapping[str, object]] | Sequence[Sequence[object]],
    header: Sequence[str] | None = None,
    digits: int = 3,
) -> str:
    """A Markdown table (display it with ``IPython.display.Markdown``).

    Parameters
    ----------
    rows : sequence of mappings or of sequences
        One entry per row. Mappings give their keys as the header (the first row's, in order).
    header : sequence of str, optional
        Column titles; required when the rows are sequences.
    digits : int
        Decimals for floats; everything else is shown with ``str``.
    """
    if not rows:
        raise ValueError("markdown_table needs at least one row")
    if isinstance(rows[0], Mapping):
        header = list(header or rows[0])
        cells = [[r.get(c, "") for c in header] for r in rows]  # type: ignore[union-attr]
    else:
        if header is None:
            raise ValueError("markdown_table needs a header when the rows are sequences")
        header, cells = list(header), [list(r) for r in rows]  # type: ignore[arg-type]
    if any(len(r) != len(header) for r in cells):
        raise ValueError(f"every row needs {len(header)} cells, one per column of {header}")

    def fmt(x: object) -> str:
        if isinstance(x, (float, np.floating)):
            return f"{x:.{digits}f}"
        return str(x)

    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(fmt(x) for x in r) + " |" for r in cells]
    return "\n".join(lines)


def draw_collisions(sim, episodes: Sequence, title: Callable[[object], str], most: int = 4) -> plt.Figure:
    """Up to ``most`` colliding episodes side by side: map, path, and the robot red where it touched.

    ``title(episode)`` gives each panel's title; ``sim`` reloads each episode's world. The cylinders
    are drawn where they stood when the colliding primitive started (they move on the moving course).
    """
    shown = list(episodes)[:most]
    fig, axes = plt.subplots(1, len(shown), figsize=(4.2 * len(shown), 3.2), squeeze=False)
    for ax, e in zip(axes[0], shown, strict=True):
        world = sim.load(e.world_seed)
        draw_world(world, ax, e.poses[0], t=e.n_prims - 1)
        draw_path(e.path, ax, lw=2)
        draw_robot(e.poses[-1], world.config.robot_radius, ax, "tab:red")
        ax.set_title(title(e), fontsize=9)
    return fig
