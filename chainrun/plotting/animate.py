"""An animation of a run: the balls as discs moving along the line, coloured by velocity.

One frame per snapshot (every s-th when there are more than ``MAX_FRAMES``), drawn from
the run file alone. A ball of the schematic has diameter 1 in the paper's unit of
length and is drawn at its reference place plus its displacement, so pressed balls
overlap by their compression. GIF is written by Pillow (a dependency of matplotlib);
MP4 needs the ``ffmpeg`` program.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from chainrun.errors import ChainrunError

__all__ = ["MAX_BALLS", "MAX_FRAMES", "animate_run"]

MAX_FRAMES = 400
MAX_BALLS = 300
DPI = 100


def _frames(run) -> np.ndarray:
    if run.times.size < 2:
        raise ChainrunError(f"{run.path}: an animation needs at least 2 snapshots, the file "
                            f"has {run.times.size} (set output.times in the experiment)")
    stride = -(-run.times.size // MAX_FRAMES)
    return np.arange(0, run.times.size, stride)


def animate_run(path, out, *, balls: tuple[int, int] | None = None, fps: int = 20) -> Path:
    """Write the animation of the run file ``path`` to ``out`` (``.gif`` or ``.mp4``).

    ``balls`` = (first, last), 1-based and inclusive, picks the balls shown (default:
    all, at most ``MAX_BALLS`` from the first). Returns ``out``.

    Raises
    ------
    ChainrunError
        For a file that is not a run file, too few snapshots, a bad ball range, an
        unknown movie format, or MP4 without ffmpeg.
    """
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
    from matplotlib.collections import EllipseCollection
    from matplotlib.figure import Figure

    from chainrun import atomic
    from chainrun.plotting import style
    from chainrun.units import PAPER as UNITS
    from chainrun.store import read_run

    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ChainrunError(f"{out}: a movie is .gif or .mp4, not {suffix or 'no suffix'!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ChainrunError(f"{out}: MP4 needs the ffmpeg program, which is not installed; "
                            "write a .gif instead (no program needed)")
    run = read_run(path)
    first, last = balls if balls is not None else (1, min(run.n, MAX_BALLS))
    if not 1 <= first <= last <= run.n:
        raise ChainrunError(f"balls {first}:{last}: not within 1:{run.n}")
    frames = _frames(run)
    cols = slice(first - 1, last)
    x = np.asarray(run.positions[:, cols])[frames]
    v = np.asarray(run.velocities[:, cols])[frames]
    place = np.arange(first, last + 1, dtype=float)
    top = float(np.max(np.abs(v))) or 1.0

    with style():
        figure = Figure(figsize=(8.0, 2.4), layout="constrained")
        axes = figure.add_subplot()
        centres = np.column_stack([place + x[0], np.zeros(place.size)])
        discs = EllipseCollection(np.ones(place.size), np.ones(place.size), 0.0,
                                  units="x", offsets=centres, offset_transform=axes.transData,
                                  cmap="RdBu_r", edgecolors="black", linewidths=0.4,
                                  gid="balls")
        discs.set_array(v[0])
        discs.set_clim(-top, top)
        axes.add_collection(discs)
        span = (place[0] + x.min() - 1.0, place[-1] + x.max() + 1.0)
        axes.set_xlim(*span)
        axes.set_ylim(-1.0, 1.0)
        axes.set_yticks([])
        axes.set_xlabel(f"position ({UNITS}; ball diameter 1)")
        figure.colorbar(discs, ax=axes, label="velocity", fraction=0.03)
        label = axes.set_title("", loc="left", fontsize="medium")
        label.set_gid("time")

        def update(i):
            discs.set_offsets(np.column_stack([place + x[i], np.zeros(place.size)]))
            discs.set_array(v[i])
            label.set_text(f"t = {run.times[frames[i]]:.4g}")
            return discs, label

        movie = FuncAnimation(figure, update, frames=len(frames), blit=False)
        writer = PillowWriter(fps=fps) if suffix == ".gif" else FFMpegWriter(fps=fps)
        out.parent.mkdir(parents=True, exist_ok=True)
        atomic.write(out, lambda tmp: movie.save(tmp, writer=writer, dpi=DPI),
                     keep_suffix=True)
    return out
