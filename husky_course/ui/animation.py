"""Self-contained players (no kernel, no CDN): figures to scrub, as matplotlib's JavaScript.

:func:`figure_player` turns any figure function and a list of its arguments into one player (the
book's form of a live widget: precomputed frames instead of a kernel).

:func:`map_player` shows what a planner with a map remembers: left, the course from above with the
robot's path and the map's points (drawn where they are in the world, for the reader); right, the
map raster the memory student reads. ``Animation.to_jshtml`` embeds every frame in the page, so
the built book can be scrubbed offline.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import animation

from ..evaluation.episodes import Episode, run_episode
from ..planners.base import EpisodeStart, Planner
from ..sim.base import Simulator
from .plotting import draw_path, draw_robot, draw_world

# matplotlib's player draws its buttons with Font Awesome from a CDN, which an offline reader lacks;
# the stylesheet is dropped and each icon replaced by a Unicode glyph.
_CDN_STYLESHEET = re.compile(r'<link rel="stylesheet"\s+href="https://[^"]*font-awesome[^"]*">')
_GLYPHS = {
    "fa fa-minus": "&minus;",
    "fa fa-plus": "+",
    "fa fa-fast-backward": "|&#x25C0;&#x25C0;",  # only glyphs every system font has
    "fa fa-step-backward": "&#x25C0;|",
    "fa fa-play fa-flip-horizontal": "&#x25C0;",
    "fa fa-pause": "||",
    "fa fa-play": "&#x25B6;",
    "fa fa-step-forward": "|&#x25B6;",
    "fa fa-fast-forward": "&#x25B6;&#x25B6;|",
}


def offline_jshtml(anim: animation.Animation) -> str:
    """``anim.to_jshtml()`` with no request to the network (buttons drawn with Unicode glyphs)."""
    html = _CDN_STYLESHEET.sub("", anim.to_jshtml(default_mode="once"))
    for css, glyph in _GLYPHS.items():
        html = html.replace(f'<i class="{css}"></i>', glyph)
    if "https://" in html or "http://" in html or '<i class="fa' in html:
        raise RuntimeError("matplotlib's to_jshtml changed: the player would ask the network for its icons")
    return html


PLAYER_DPI = 56  #: frames are rasterised at this resolution: sharp enough, ~30 kB per frame


def _raster(fig: plt.Figure, dpi: int) -> np.ndarray:
    """The figure as an RGB array at ``dpi`` (Agg), then closed."""
    fig.set_dpi(dpi)
    fig.canvas.draw()
    rgb = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    plt.close(fig)
    return rgb


def figure_player(
    figure: Callable[..., plt.Figure], frames: list[dict], dpi: int = PLAYER_DPI, interval_ms: int = 900
) -> str:
    """HTML of a player whose frame ``i`` is ``figure(**frames[i])`` (``to_jshtml``: no kernel, no CDN).

    Each figure is drawn once, rasterised at ``dpi`` and shown pixel for pixel (frames of different
    sizes are padded white to the largest), so the page weighs about ``len(frames)`` small PNGs.
    """
    if not frames:
        raise ValueError("figure_player needs at least one frame")
    images = [_raster(figure(**kwargs), dpi) for kwargs in frames]
    height = max(im.shape[0] for im in images)
    width = max(im.shape[1] for im in images)
    padded = []
    for im in images:
        canvas = np.full((height, width, 3), 255, np.uint8)
        canvas[: im.shape[0], : im.shape[1]] = im
        padded.append(canvas)
    fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    shown = ax.imshow(padded[0], interpolation="nearest")

    def draw(i: int) -> tuple:
        shown.set_data(padded[i])
        return (shown,)

    anim = animation.FuncAnimation(fig, draw, frames=len(padded), interval=interval_ms, blit=False)
    html = offline_jshtml(anim)
    plt.close(fig)
    return html


@dataclass
class MapFrame:
    """One decision: the robot's pose, its map in the world frame, the raster it read, its action."""

    pose: np.ndarray
    points: np.ndarray
    raster: np.ndarray | None
    action: int


class _Recorder(Planner):
    """Wraps a planner that keeps ``map`` (an EgoMap) and records it after every decision."""

    def __init__(self, inner: Planner) -> None:
        super().__init__()
        self.inner, self.name, self.privileged = inner, inner.name, False
        self.maps: list[tuple[np.ndarray, np.ndarray | None]] = []

    def reset(self, start: EpisodeStart) -> None:
        self.inner.reset(start)
        self.maps = []

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        action = self.inner.act(obs)
        last = getattr(self.inner, "last_input", None)
        self.maps.append((self.inner.map.points.copy(), None if last is None else last[1]))  # type: ignore[attr-defined]
        self.last_scores = self.inner.last_scores
        return action

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        self.inner.observe(action, obs_next)


def record_map_episode(planner: Planner, sim: Simulator, world_seed: int) -> tuple[Episode, list[MapFrame]]:
    """Run ``planner`` (one with an ``EgoMap`` called ``map``) and keep its map at every decision."""
    rec = _Recorder(planner)
    episode = run_episode(rec, sim, world_seed)
    frames = []
    for (points, raster), pose, action in zip(rec.maps, episode.poses[:-1], episode.actions, strict=True):
        world_xy = points[:, :2] + pose[:2]  # robot frame -> world (the heading is 0 at every decision)
        frames.append(MapFrame(pose.copy(), world_xy, raster, int(action)))
    return episode, frames


def map_player(sim: Simulator, episode: Episode, frames: list[MapFrame], interval_ms: int = 900) -> str:
    """HTML of a scrubbable player over ``frames`` (``Animation.to_jshtml``: no kernel, no CDN)."""
    world = sim.load(episode.world_seed)
    with_raster = frames and frames[0].raster is not None
    fig, axes = plt.subplots(1, 2 if with_raster else 1, figsize=(10, 3.6), squeeze=False,
                             gridspec_kw={"width_ratios": [2.6, 1] if with_raster else [1]})
    ax_map = axes[0, 0]
    samples = sim.library.config.samples

    def draw(i: int) -> None:
        f = frames[i]
        ax_map.clear()
        draw_world(world, ax_map, f.pose)
        draw_path(episode.path[: 1 + i * samples], ax_map, lw=2)
        ax_map.scatter(f.points[:, 0], f.points[:, 1], s=4, c="k", zorder=5, label="map points")
        end = episode.poses[i + 1]
        hit = episode.collided and i == len(frames) - 1
        draw_robot(end, world.config.robot_radius, ax_map, "tab:red" if hit else "tab:purple")
        title = f"step {i + 1} of {len(frames)}: primitive {f.action}" + (" (collision)" if hit else "")
        ax_map.set_title(title, fontsize=9)
        ax_map.legend(loc="upper left", fontsize=7)
        if with_raster:
            ax = axes[0, 1]
            ax.clear()
            ax.imshow(f.raster if f.raster.ndim == 2 else f.raster[0], cmap="Greys", vmin=0, vmax=1)
            ax.set_title("what the student reads: its map", fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])

    anim = animation.FuncAnimation(fig, draw, frames=len(frames), interval=interval_ms)
    html = offline_jshtml(anim)
    plt.close(fig)
    return html


def course_frame(sim: Simulator, episode: Episode, step: int, title: str = "") -> plt.Figure:
    """The course at time ``step`` (cylinders where they are then) with the robot's path so far."""
    world = sim.load(episode.world_seed)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    step = min(step, len(episode.poses) - 1)
    draw_world(world, ax, episode.poses[step], t=step)
    samples = sim.library.config.samples
    draw_path(episode.path[: 1 + step * samples], ax, lw=2)
    hit = episode.collided and step == len(episode.poses) - 1
    if hit:
        draw_robot(episode.poses[step], world.config.robot_radius, ax, "tab:red")
    end = " (collision)" if hit else ""
    ax.set_title(f"{title}time {step} of {len(episode.poses) - 1}{end}", fontsize=9)
    return fig


def course_player(sim: Simulator, episode: Episode, title: str = "") -> str:
    """HTML of a player over an episode's steps: the course at every time, the robot's path so far
    (moving cylinders where they are at that time; :func:`figure_player`, no kernel, no CDN)."""
    frames = [{"sim": sim, "episode": episode, "step": k, "title": title} for k in range(len(episode.poses))]
    return figure_player(course_frame, frames)
