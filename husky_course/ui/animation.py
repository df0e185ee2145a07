"""Self-contained players (no kernel, no CDN): an episode step by step, as matplotlib's JavaScript.

:func:`map_player` shows what a planner with a map remembers: left, the course from above with the
robot's path and the map's points (drawn where they are in the world, for the reader); right, the
map raster the memory student reads. ``Animation.to_jshtml`` embeds every frame in the page, so
the built book can be scrubbed offline.
"""

from __future__ import annotations

from dataclasses import dataclass

import matplotlib.pyplot as plt
import numpy as np
from matplotlib import animation

from ..evaluation.episodes import Episode, run_episode
from ..planners.base import EpisodeStart, Planner
from ..sim.base import Simulator
from .plotting import draw_path, draw_robot, draw_world


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
            ax.imshow(f.raster, cmap="Greys", vmin=0, vmax=1)
            ax.set_title("what the student reads: its map", fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])

    anim = animation.FuncAnimation(fig, draw, frames=len(frames), interval=interval_ms)
    html = anim.to_jshtml(default_mode="once")
    plt.close(fig)
    return html
