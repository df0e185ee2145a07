"""Interactive widgets, each with a static fallback.

In a live Jupyter kernel with ipywidgets, :func:`world_explorer` shows a slider; wherever widgets
cannot run (the built book read offline, CI, ``HUSKY_STATIC_WIDGETS=1``), it draws the same figure
once at its default value, so the page never shows an empty box.
"""

from __future__ import annotations

import os

import matplotlib.pyplot as plt

from .backends import make_simulator
from .config import SimConfig
from .plotting import figure_two


def widgets_live() -> bool:
    """True when interactive widgets can render (a kernel with ipywidgets, not a static run)."""
    if os.environ.get("HUSKY_STATIC_WIDGETS") or os.environ.get("CI"):
        return False
    try:
        import ipywidgets  # noqa: F401
        from IPython import get_ipython
    except ImportError:
        return False
    shell = get_ipython()
    return shell is not None and shell.__class__.__name__ == "ZMQInteractiveShell"


def show_world(seed: int = 0, backend: str = "fast", config: SimConfig | None = None) -> plt.Figure:
    """Figure 2 for world ``seed``: RGB view, depth image and map at the start pose."""
    with make_simulator(backend, config) as sim:
        world = sim.load(int(seed))
        depth = sim.depth(world.start[None])[0]
        rgb = sim.rgb(world.start)
    return figure_two(world, depth, rgb)


def world_explorer(default_seed: int = 0, backend: str = "fast") -> None:
    """A world-seed slider around :func:`show_world` (static figure at ``default_seed`` offline)."""
    fig = show_world(default_seed, backend)
    plt.show()
    plt.close(fig)
    if not widgets_live():
        return
    import ipywidgets as w
    from IPython.display import display

    out = w.Output()
    slider = w.IntSlider(value=default_seed, min=0, max=999, description="world seed")

    def redraw(change: dict | None = None) -> None:
        with out:
            out.clear_output(wait=True)
            f = show_world(slider.value, backend)
            plt.show()
            plt.close(f)

    slider.observe(redraw, names="value")
    display(w.VBox([slider, out]))
