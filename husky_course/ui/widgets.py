"""Interactive widgets: live in a kernel, a JavaScript player (or a still figure) offline.

Every widget goes through :func:`interactive_figure`: in a live Jupyter kernel with ipywidgets it
shows sliders and dropdowns above one figure that is redrawn in place; wherever widgets cannot run
(the built book read offline: ``make book`` sets ``HUSKY_STATIC_WIDGETS=1``) it precomputes the
figure for a few values of the controls into a player that needs no kernel and no CDN, so the page
never shows an empty box and a reader can still scrub.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
import torch

from ..config import EvalPlan, SimConfig
from ..evaluation.episodes import Episode, eval_world_seeds, run_episode
from ..progress import static_mode
from ..sim.backends import make_simulator
from ..sim.base import Simulator
from ..sim.fast import FastSimulator
from ..sim.world import World
from .animation import figure_player
from .plotting import draw_path, draw_robot, draw_world, figure_two, show_depth


def widgets_live() -> bool:
    """True when interactive widgets can render (a kernel with ipywidgets, not a static run)."""
    if static_mode():
        return False
    try:
        import ipywidgets  # noqa: F401
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and shell.__class__.__name__ == "ZMQInteractiveShell"


@dataclass(frozen=True)
class Control:
    """One widget control: an integer slider (``options = (min, max)``) or a dropdown (choices)."""

    name: str  #: the keyword argument of the figure function it sets
    description: str
    value: int | str  #: the default, also used for the static figure
    options: tuple


def interactive_figure(
    figure: Callable[..., plt.Figure],
    rows: list[list[Control]],
    frames: list[dict] | None = None,
) -> None:
    """One figure with its controls: live in a kernel, a JavaScript player (or a still) offline.

    In a live kernel with ipywidgets the controls and a single ``Output`` are shown; the figure is
    drawn into the output and redrawn *in place* whenever a control moves (never a second figure).
    Offline (the built book: ``HUSKY_STATIC_WIDGETS=1``) there is no kernel to answer a
    control: with ``frames`` (keyword overrides of the defaults, one per frame) the figures are
    precomputed into a self-contained player (:func:`~husky_course.ui.animation.figure_player`,
    no CDN), else the figure at the defaults is drawn once, so no page shows an empty box.
    """
    controls = [c for row in rows for c in row]
    defaults = {c.name: c.value for c in controls}
    from IPython.display import HTML, display

    if not widgets_live():
        if frames:
            display(HTML(figure_player(figure, [{**defaults, **f} for f in frames])))
        else:
            fig = figure(**defaults)
            plt.show()
            plt.close(fig)
        return
    import ipywidgets as w

    def make(c: Control) -> object:
        if isinstance(c.value, str):
            return w.Dropdown(options=list(c.options), value=c.value, description=c.description)
        return w.IntSlider(
            value=c.value, min=c.options[0], max=c.options[1], description=c.description,
            continuous_update=False,  # redraw when the slider is released, not at every pixel
        )

    made = {c.name: make(c) for c in controls}
    out = w.Output()

    def redraw(change: dict | None = None) -> None:
        with out:
            out.clear_output(wait=True)
            f = figure(**{name: widget.value for name, widget in made.items()})
            plt.show()
            plt.close(f)

    for widget in made.values():
        widget.observe(redraw, names="value")
    display(w.VBox([w.HBox([made[c.name] for c in row]) for row in rows] + [out]))
    redraw()


def show_world(seed: int = 0, backend: str = "fast", config: SimConfig | None = None) -> plt.Figure:
    """Figure 2 for world ``seed``: RGB view, depth image and map at the start pose."""
    with make_simulator(backend, config) as sim:
        world = sim.load(int(seed))
        depth = sim.depth(world.start[None])[0]
        rgb = sim.rgb(world.start)
    return figure_two(world, depth, rgb)


def world_explorer(default_seed: int = 0, backend: str = "fast", player_worlds: int = 8) -> None:
    """A world-seed slider around :func:`show_world`; offline, a player over ``player_worlds`` seeds."""
    interactive_figure(
        lambda seed: show_world(seed, backend),
        [[Control("seed", "world seed", default_seed, (0, 999))]],
        frames=[{"seed": default_seed + i} for i in range(player_worlds)],
    )


# --- planning widgets (chapter 7) -------------------------------------------------------------------
def predicted_next_image(planner: object, obs: np.ndarray, action: int) -> np.ndarray | None:
    """What a learned planner's model expects to see after ``action`` (``None`` if it cannot say)."""
    model = getattr(planner, "model", None)
    image = torch.from_numpy(np.asarray(obs, np.float32))[None]
    with torch.no_grad():
        if model is not None and hasattr(model, "decoder"):
            return model.decoder(model.encoder(image), torch.tensor([int(action)]))[0].numpy()
        if model is not None and hasattr(model, "rollout"):
            img, _ = model.rollout(model.start(image), torch.tensor([[int(action)]]))
            return torch.sigmoid(img[0, 0]).numpy()
    return None


def draw_planner_step(
    world: World, episode: Episode, step: int, planner: object, sim: Simulator
) -> plt.Figure:
    """One decision of a recorded episode: map so far, scores, current / predicted / real next image."""
    step = int(np.clip(step, 0, len(episode.actions) - 1))
    action = episode.actions[step]
    fig = plt.figure(figsize=(12, 4.6))
    grid = fig.add_gridspec(2, 4, width_ratios=[2.4, 1, 1, 1])
    ax_map = fig.add_subplot(grid[:, 0])
    draw_world(world, ax_map, episode.poses[step])
    ends = np.cumsum([0] + [sim.library.config.samples] * len(episode.actions)) + 1
    draw_path(episode.path[: ends[step + 1]], ax_map, lw=2)
    if step + 1 < len(episode.poses):
        draw_robot(
            episode.poses[step + 1],
            world.config.robot_radius,
            ax_map,
            "tab:red" if (episode.collided and step == len(episode.actions) - 1) else "tab:purple",
        )
    outcome = "collision" if episode.collided else ("crossed" if episode.success else "stopped")
    who = getattr(planner, "name", "")
    where = f"world {world.seed}: step {step + 1} of {len(episode.actions)} ({outcome})"
    ax_map.set_title(f"{who}, {where}" if who else where, fontsize=9)
    ax_bar = fig.add_subplot(grid[0, 1:])
    scores = episode.scores[step] if step < len(episode.scores) else None
    if scores is not None:
        finite = np.where(np.isfinite(scores), scores, np.nan)
        colours = ["tab:red" if k == action else "tab:blue" for k in range(len(finite))]
        ax_bar.bar(np.arange(len(finite)), finite, color=colours)
        ax_bar.set_ylabel("score (lower is better)", fontsize=8)
    else:
        ax_bar.text(0.5, 0.5, "this planner keeps no scores", ha="center", va="center")
    last = sim.library.n - 1
    ax_bar.set_xlabel(f"primitive (chosen: {action}; 0 = far right, {last} = far left)", fontsize=8)
    obs = episode.observations[step]
    predicted = predicted_next_image(planner, obs, action)
    real = (
        None
        if (episode.collided and step == len(episode.actions) - 1)
        else sim.depth(episode.poses[step + 1][None], step + 1)[0]
    )
    for j, (img, title) in enumerate(
        ((obs, "image now"), (predicted, "predicted next"), (real, "real next"))
    ):
        ax = fig.add_subplot(grid[1, 1 + j])
        if img is None:
            ax.set_axis_off()
            ax.text(0.5, 0.5, "collision" if title == "real next" else "no prediction", ha="center")
        else:
            show_depth(img, ax, title)
    fig.tight_layout()
    return fig


def planner_stepper(
    make: Callable[[str, int], object],
    planners: tuple[str, ...],
    default_seed: int,
    default_planner: str,
    default_look_ahead: int = EvalPlan.look_ahead,
    default_step: int = 0,
    seeds: tuple[int, int] = (0, 99),
    sim: Simulator | None = None,
) -> None:
    """Step through a planner's decisions in a held-out world.

    ``make(name, look_ahead)`` builds a planner; world seeds are held-out evaluation seeds
    (:func:`husky_course.evaluation.episodes.eval_world_seeds`), indexed by the slider. Offline, a
    player steps through the default world's episode of every planner in ``planners`` in turn.
    """
    sim = sim or FastSimulator()
    cache: dict[tuple, tuple] = {}

    def episode_of(seed_index: int, name: str, look_ahead: int) -> tuple:
        key = (seed_index, name, look_ahead)
        if key not in cache:
            planner = make(name, look_ahead)
            world_seed = int(eval_world_seeds(seed_index + 1)[seed_index])
            cache[key] = (planner, run_episode(planner, sim, world_seed, record=True))
        return cache[key]

    def figure(seed_index: int, name: str, look_ahead: int, step: int) -> plt.Figure:
        planner, episode = episode_of(seed_index, name, look_ahead)
        return draw_planner_step(
            sim.world if sim.world and sim.world.seed == episode.world_seed else sim.load(episode.world_seed),
            episode,
            step,
            planner,
            sim,
        )

    frames = (
        []
        if widgets_live()
        else [
            {"name": name, "step": step}
            for name in planners
            for step in range(len(episode_of(default_seed, name, default_look_ahead)[1].actions))
        ]
    )
    interactive_figure(
        figure,
        [
            [
                Control("seed_index", "world", default_seed, seeds),
                Control("name", "planner", default_planner, tuple(planners)),
            ],
            [
                Control("look_ahead", "look_ahead", default_look_ahead, (0, 4)),
                Control("step", "step", default_step, (0, sim.config.max_primitives - 1)),
            ],
        ],
        frames=frames,
    )


def primitive_explorer(
    model: object, default_seed: int = 0, default_primitive: int = 12, sim: Simulator | None = None
) -> None:
    """Choose a primitive: the model's predicted next depth image beside the simulator's."""
    sim = sim or FastSimulator()

    def figure(seed_index: int, k: int) -> plt.Figure:
        world = sim.load(int(eval_world_seeds(seed_index + 1)[seed_index]))
        obs = sim.depth(world.start[None])[0]
        result = sim.apply(world.start, int(k))
        predicted = predicted_next_image(type("P", (), {"model": model})(), obs, int(k))
        fig, axes = plt.subplots(1, 4, figsize=(12, 3), gridspec_kw={"width_ratios": [2.2, 1, 1, 1]})
        draw_world(world, axes[0])
        draw_path(result.path, axes[0], "tab:red" if result.collided else "tab:green", lw=2)
        axes[0].set_title(f"primitive {k}: {'collides' if result.collided else 'safe'}", fontsize=9)
        show_depth(obs, axes[1], "image now")
        if predicted is not None:
            show_depth(predicted, axes[2], "predicted next")
        real = sim.depth(result.pose[None], 1)[0]
        show_depth(real, axes[3], "real next" + (" (stopped at contact)" if result.collided else ""))
        fig.tight_layout()
        return fig

    interactive_figure(
        figure,
        [
            [
                Control("seed_index", "world", default_seed, (0, 99)),
                Control("k", "primitive", default_primitive, (0, sim.library.n - 1)),
            ]
        ],
        frames=[{"k": k} for k in range(sim.library.n)],
    )
