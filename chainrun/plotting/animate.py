"""A movie of a run: the balls as discs moving along the line, coloured by velocity.

This module owns how a run is drawn as a movie and how its frames are written. One
frame per snapshot (every s-th when there are more than ``MAX_FRAMES``), drawn from
the run file alone.

Where the balls are drawn. A line of real spheres (an SI run with diameters) is drawn
to scale: each ball at its true diameter, touching its neighbours at rest, ball 1's
left side at position 0. Displacements of a few micrometres against beads of
millimetres would not show, so every displacement from the initial state and gap is
drawn magnified by a factor written on the frame: ball i's centre is at its place at
rest plus ``x_i(0) + magnify * (g_1 + ... + g_(i-1) + x_i(t) - x_i(0))`` (a gap < 0,
an initial overlap, counts in x_i(0)). The initial state is drawn true to scale (a
precompressed line's static squeeze, micrometres, does not show), the motion from it
magnified. Pressed balls then overlap by their magnified
compression beyond the initial one, and a wall stands its magnified gap away from the
end ball. A
line without diameters (the paper's line, or masses and stiffnesses given directly)
is a schematic: ball n at place n, one paper unit of length wide, with the same
magnified motion. The automatic factor (1, 2 or 5 times a power of ten) makes the
largest compression beyond the initial one ``COMPRESSION_SHOWN`` of the smallest
diameter, unless that would make the magnified motion longer than the line itself.

Frames are drawn by blitting: the figure (axes, walls, colour bar, labels) is drawn
once, and each frame restores it and draws only the balls and the time. GIF frames
share one palette and are written by Pillow (a dependency of matplotlib); MP4 frames
are piped to the ``ffmpeg`` program.
"""

from __future__ import annotations

import itertools
import math
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from chainrun.errors import ChainrunError
from chainrun.units import PAPER, Scaled, axis_label, format_value, scale_for

__all__ = ["COMPRESSION_SHOWN", "MAX_BALLS", "MAX_FRAMES", "animate_run", "movie_figure"]

MAX_FRAMES = 400
MAX_BALLS = 300
#: size of a frame: 800 x 240 pixels
FIGSIZE = (8.0, 2.4)
DPI = 100
#: the frames' width in pixels by default (FIGSIZE at DPI), and the widths allowed
WIDTH, MIN_WIDTH, MAX_WIDTH = 800, 320, 3840
#: characters of a line of the title
TITLE_WIDTH = 110
#: the colours of velocity, red forward and blue backward
CMAP = "RdBu_r"
#: the automatic magnification draws the largest compression as this fraction of the
#: smallest diameter
COMPRESSION_SHOWN = 0.25


@dataclass(frozen=True)
class Picture:
    """Where the balls and walls of a run are drawn, in the drawing's unit of length.

    Attributes
    ----------
    length : Scaled
        From the run's unit of length to the drawing's (``mm`` for real spheres; a
        schematic's ``""``, where 1 is one paper unit of length).
    place : ndarray, shape (n,)
        Centre of each ball shown at rest, touching, without gaps.
    width : ndarray, shape (n,)
        Diameter of each ball shown.
    start : ndarray, shape (n,)
        Each ball's initial displacement plus the initial overlaps (gaps < 0) before
        it, in the run's unit of length: scaled by ``length``, it is added to
        ``place``.
    motion : ndarray, shape (F, n)
        Gaps before each ball plus its displacement from ``start`` at each frame, in
        the run's unit of length: magnified, then scaled by ``length``, it is added to
        ``place`` and ``start``.
    walls : dict of str to (float, float, float)
        For each wall drawn ("left", "right"): its face at rest (drawing's unit), and
        its overlap's and its gap's shares of the start and of the motion (the run's
        unit), as for a ball.
    compression : float
        The largest compression of a contact or wall over the frames beyond its
        initial one, if that was pressed (run's unit).
    to_scale : bool
        Whether the balls are real spheres drawn to scale (else a schematic).
    """

    length: Scaled
    place: np.ndarray
    width: np.ndarray
    start: np.ndarray
    motion: np.ndarray
    walls: dict
    compression: float
    to_scale: bool

    def centres(self, magnify: float) -> np.ndarray:
        """Centres of the balls at each frame, shape (F, n)."""
        return self.place + self.length(self.start + magnify * self.motion)

    def wall_faces(self, magnify: float) -> dict[str, float]:
        """Where each wall's face is drawn."""
        return {side: face + float(self.length(start + magnify * gap))
                for side, (face, start, gap) in self.walls.items()}

    def auto_magnify(self) -> float:
        """The largest of 1, 2, 5 times a power of ten that shows the largest
        compression as at most ``COMPRESSION_SHOWN`` of the smallest diameter and keeps
        the magnified motion (of the balls and walls shown) within the line's length."""
        one = float(self.length(1.0))  # a unit of the run's length, drawn
        limits = []
        if self.compression > 0.0:
            limits.append(COMPRESSION_SHOWN * float(self.width.min())
                          / (self.compression * one))
        spread = np.concatenate([self.motion.ravel(),
                                 [gap for _, _, gap in self.walls.values()]])
        if np.ptp(spread) > 0.0:
            line = float(self.place[-1] - self.place[0]
                         + (self.width[0] + self.width[-1]) / 2.0)
            limits.append(line / (float(np.ptp(spread)) * one))
        if not limits:
            return 1.0
        top = min(limits)
        power = 10.0 ** math.floor(math.log10(top))
        return max(step * power for step in (1.0, 2.0, 5.0) if step * power <= top * (1 + 1e-9))


def _picture(run, frames: np.ndarray, first: int, last: int) -> Picture:
    """Where balls ``first``..``last`` (1-based, inclusive) and the walls next to them
    are drawn in ``frames`` (snapshot indices) of ``run`` (``chainrun.store.RunData``)."""
    line, units, n = run.line, run.units, run.n
    cols = slice(first - 1, last)
    x = np.asarray(run.positions[:, cols])[frames]
    gap = np.asarray(line.gap, dtype=float)
    # a gap is drawn magnified, an initial overlap (a gap < 0) true to scale, as the
    # initial displacements: each ball's share of the gaps before it, (N,)
    before = np.concatenate([[0.0], np.cumsum(np.maximum(gap, 0.0))])
    overlap = np.concatenate([[0.0], np.cumsum(np.minimum(gap, 0.0))])
    if line.diameter is not None:
        diameter = np.asarray(line.diameter, dtype=float)
        rest = np.cumsum(diameter) - diameter / 2.0  # ball 1's left side at 0
        length = scale_for("position", units, [rest[-1] + diameter[-1] / 2.0])
        place, width = length(rest), length(diameter)
    else:
        # a schematic: ball n at n, one paper unit of length wide (in SI, the line's
        # own paper unit, model/scales@length)
        unit = float(run.model["scales"]["length"]) if units == "si" else 1.0
        length = Scaled(1.0 / unit, "")
        place, width = np.arange(1.0, n + 1.0), np.ones(n)

    x0 = np.asarray(line.position, dtype=float)[cols]

    def squeeze(x):
        """Compressions of the contacts between the balls shown and of the walls beside
        them, at each row of x."""
        out = [x[:, :-1] - x[:, 1:] - gap[first - 1:last - 1]]
        if line.left is not None and first == 1:
            out.append(-x[:, :1] - line.left.gap)
        if line.right is not None and last == n:
            out.append(x[:, -1:] - line.right.gap)
        return np.concatenate(out, axis=1)

    drawn = {}
    if line.left is not None and first == 1:
        g = line.left.gap
        drawn["left"] = (float(place[0] - width[0] / 2.0), -min(g, 0.0), -max(g, 0.0))
    if line.right is not None and last == n:
        g = line.right.gap
        drawn["right"] = (float(place[-1] + width[-1] / 2.0),
                          float(overlap[-1]) + min(g, 0.0), float(before[-1]) + max(g, 0.0))
    # beyond the initial compression where that was pressed (a static load)
    beyond = squeeze(x) - np.maximum(squeeze(x0[None, :]), 0.0)
    compression = float(np.max(beyond, initial=0.0))
    return Picture(length=length, place=place[cols], width=width[cols],
                   start=x0 + overlap[cols], motion=before[cols] + x - x0, walls=drawn,
                   compression=compression, to_scale=line.diameter is not None)


def _frames(run) -> np.ndarray:
    if run.times.size < 2:
        raise ChainrunError(f"{run.path}: an animation needs at least 2 snapshots, the file "
                            f"has {run.times.size} (set output.times in the experiment)")
    stride = -(-run.times.size // MAX_FRAMES)
    return np.arange(0, run.times.size, stride)


def _title(run, first: int, last: int) -> str:
    """The experiment (and run) name, the balls shown if not all, over what the line
    is (``views.describe``)."""
    from chainrun.plotting.views import describe

    run_id = run.parameters.get("run_id", "")
    name = run.parameters.get("experiment", "") + (
        f" ({run_id})" if run_id and run_id != "run" else "")
    if (first, last) != (1, run.n):
        name += f", balls {first} to {last} shown"
    return "\n".join([name] * bool(name) + [describe(run, width=TITLE_WIDTH)])


def _magnified(factor: float) -> str:
    """How much the motion is drawn magnified, in words: ``"magnified 200,000 times"``
    (a whole number with its thousands marked), ``"true to scale"``, ``"scaled by
    0.5"``."""
    if factor == 1.0:
        return "true to scale"
    if factor < 1.0:
        return f"scaled by {factor:g}"
    whole = factor == math.floor(factor) and factor < 1e15
    return f"magnified {int(factor):,} times" if whole else f"magnified {factor:g} times"


def _clock(times: np.ndarray, units: str) -> list[str]:
    """The text of each frame's time, in one unit for the whole movie and with one
    number of decimals: the fewest that write every time exactly, at most those of 4
    significant digits of the largest, but enough to tell the frames apart."""
    scaled = scale_for("time", units, times)
    t = scaled(times)
    largest = float(np.abs(t).max())
    most = max(3 - math.floor(math.log10(largest)), 0) if largest > 0.0 else 0
    decimals = next((d for d in range(most + 1)
                     if np.allclose(np.round(t, d), t, rtol=0.0, atol=1e-9 * largest)), most)
    while decimals < 12 and np.any((np.diff(np.round(t, decimals)) == 0) & (np.diff(t) != 0)):
        decimals += 1
    unit = scaled.unit if units == "si" else f"({PAPER})"
    return [f"t = {value:.{decimals}f} {unit}" for value in t]


def animate_run(path, out, *, balls: tuple[int, int] | None = None, fps: int = 20,
                magnify: float | None = None, width: int = WIDTH) -> Path:
    """Write the movie of the run file ``path`` to ``out`` (``.gif`` or ``.mp4``).

    Parameters
    ----------
    path : path-like
        A run file.
    out : path-like
        The movie; its suffix picks the format.
    balls : (int, int), optional
        (first, last), 1-based and inclusive: the balls shown (default: all, at most
        ``MAX_BALLS`` from the first).
    fps : int
        Frames per second.
    magnify : float, optional
        How much displacements and gaps are magnified (default:
        ``Picture.auto_magnify``, as the module's docstring says).
    width : int
        The frames' width in pixels (their height follows, and the text with them).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    ChainrunError
        For a file that is not a run file, too few snapshots, a bad ball range or
        magnification, an unknown movie format, or MP4 without ffmpeg.
    """
    from chainrun import atomic
    from chainrun.plotting import style
    from chainrun.store import read_run

    out = Path(out)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ChainrunError(f"{out}: a movie is .gif or .mp4, not {suffix or 'no suffix'!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ChainrunError(f"{out}: MP4 needs the ffmpeg program, which is not installed; "
                            "write a .gif instead (no program needed)")
    if magnify is not None and not (math.isfinite(magnify) and magnify > 0.0):
        raise ChainrunError(f"magnify {magnify}: must be a positive number")
    if not MIN_WIDTH <= width <= MAX_WIDTH:
        raise ChainrunError(f"width {width}: frames are {MIN_WIDTH} to {MAX_WIDTH} pixels wide")
    run = read_run(path)
    first, last = balls if balls is not None else (1, min(run.n, MAX_BALLS))
    if first > last:
        raise ChainrunError(f"balls {first}:{last}: the first is after the last (give "
                            f"FIRST:LAST, e.g. {last}:{first})")
    if not 1 <= first <= last <= run.n:
        raise ChainrunError(f"balls {first}:{last}: not within 1:{run.n}")
    frames = _frames(run)
    with style():
        figure, draw = movie_figure(run, frames, first, last, magnify=magnify,
                                    dpi=width / FIGSIZE[0])
        out.parent.mkdir(parents=True, exist_ok=True)
        write = _write_gif if suffix == ".gif" else _write_mp4
        atomic.write(out, lambda tmp: write(tmp, figure, draw, len(frames), fps),
                     keep_suffix=True)
    return out


def movie_figure(run, frames, first: int, last: int, *, magnify: float | None = None,
                 dpi: float = DPI):
    """The movie's figure and a function that draws frame i on it (``draw(i)``).

    The figure is laid out with the last frame's time; ``draw`` sets the balls and the
    time of frame i and returns the artists that change. Artists carry a ``gid``:
    ``balls``, ``time``, ``magnification``, ``wall/left``, ``wall/right``. Must be
    called inside ``chainrun.plotting.style()``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import EllipseCollection
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    units = run.units
    shown = _picture(run, frames, first, last)
    magnify = shown.auto_magnify() if magnify is None else float(magnify)
    centres = shown.centres(magnify)
    faces = shown.wall_faces(magnify)
    v = np.asarray(run.velocities[:, first - 1:last])[frames]
    v_label, v_scaled = axis_label("velocity", "velocity", units, v)
    v = v_scaled(v)
    top = float(np.max(np.abs(v))) or 1.0
    clock = _clock(run.times[frames], units)

    figure = Figure(figsize=FIGSIZE, dpi=dpi, layout="constrained")
    axes = figure.add_subplot()
    axes.set_aspect("equal", adjustable="datalim")
    big = float(shown.width.max())
    discs = EllipseCollection(shown.width, shown.width, 0.0, units="xy",
                              offsets=np.column_stack([centres[-1], np.zeros(centres.shape[1])]),
                              offset_transform=axes.transData, cmap=CMAP,
                              edgecolors="black", linewidths=0.4, gid="balls", animated=True)
    discs.set_array(v[-1])
    discs.set_clim(-top, top)
    axes.add_collection(discs)
    # a wall as thick as a third of a ball, and at least 1% of the line, or a long line's
    # walls are slivers a few pixels wide
    span = float(centres.max() - centres.min()) + big
    thick = max(0.3 * big, 0.01 * span)
    for side, face in faces.items():
        corner = face if side == "right" else face - thick
        axes.add_patch(Rectangle((corner, -0.9 * big), thick, 1.8 * big, hatch="////",
                                 facecolor="0.85", edgecolor="0.2", linewidth=0.6,
                                 gid=f"wall/{side}"))
    low = min([float((centres - shown.width / 2).min())]
              + [face - thick for face in faces.values()])
    high = max([float((centres + shown.width / 2).max())]
               + [face + thick for face in faces.values()])
    box = ((low - 0.3 * big, high + 0.3 * big), (-big, big))  # around every frame
    axes.set_yticks([])
    if shown.to_scale:
        axes.set_xlabel(f"position along the line ({shown.length.unit})")
    else:
        one = ("lengths in " + PAPER if units != "si" else
               "1 = " + format_value(1.0 / shown.length.factor, "position", units))
        axes.set_xlabel(f"ball (schematic: ball n at n, 1 wide; {one})")
    gaps = np.any(np.asarray(run.line.gap) > 0.0) or any(
        g for _, _, g in shown.walls.values())
    moved = "displacements since t = 0" if np.any(shown.start) else "displacements"
    stated = moved + (" and gaps" if gaps else "") + ", " + _magnified(magnify)
    axes.set_title(stated, loc="right", fontsize="medium").set_gid("magnification")
    time = axes.set_title(clock[-1], loc="left", fontsize="medium")
    time.set_gid("time")
    figure.suptitle(_title(run, first, last), fontsize="medium")
    figure.colorbar(discs, ax=axes, label=v_label, fraction=0.03)
    # lay the figure out once, then widen the box to the axes' shape at equal scales
    FigureCanvasAgg(figure).draw()
    figure.set_layout_engine("none")
    wide, tall = axes.get_window_extent().size
    (x0, x1), (y0, y1) = box
    scale = max((x1 - x0) / wide, (y1 - y0) / tall)  # length per pixel
    axes.set(xlim=((x0 + x1 - scale * wide) / 2, (x0 + x1 + scale * wide) / 2),
             ylim=((y0 + y1 - scale * tall) / 2, (y0 + y1 + scale * tall) / 2))

    def draw(i: int):
        discs.set_offsets(np.column_stack([centres[i], np.zeros(centres.shape[1])]))
        discs.set_array(v[i])
        time.set_text(clock[i])
        return discs, time

    return figure, draw


def _frames_rgb(figure, draw, count: int):
    """The frames as RGB arrays, shape (height, width, 3): the figure without the
    changing artists is drawn once, and each frame is that plus the artists ``draw(i)``
    returns."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(figure)
    changing = draw(count - 1)
    for artist in changing:
        artist.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(figure.bbox)
    for i in range(count):
        canvas.restore_region(background)
        for artist in draw(i):
            figure.draw_artist(artist)
        yield np.array(canvas.buffer_rgba())[..., :3]  # a copy: the canvas is reused


def _palette():
    """The GIF's 256 colours: 32 greys from black to white (text, lines, hatching, the
    background) and 224 colours of ``CMAP`` (the balls and the colour bar), as a "P"
    image for Pillow's ``quantize``. Pillow finds the nearest colour to within 4
    levels a channel, so the greys are 8 apart: white stays exactly white."""
    from matplotlib import colormaps
    from PIL import Image

    greys = np.repeat(np.linspace(0.0, 1.0, 32)[:, None], 3, axis=1)
    colours = colormaps[CMAP](np.linspace(0.0, 1.0, 224))[:, :3]
    palette = Image.new("P", (1, 1))
    palette.putpalette(np.round(255 * np.vstack([greys, colours])).astype(np.uint8).tobytes())
    return palette


def _write_gif(tmp: Path, figure, draw, count: int, fps: int) -> None:
    """A GIF of ``count`` frames in one palette (``_palette``), without dithering."""
    from PIL import Image

    palette = _palette()
    frames = [Image.fromarray(rgb).quantize(palette=palette, dither=Image.Dither.NONE)
              for rgb in _frames_rgb(figure, draw, count)]
    frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:],
                   duration=round(1000 / fps), loop=0)


def _write_mp4(tmp: Path, figure, draw, count: int, fps: int) -> None:
    """An H.264 MP4 made by ffmpeg from the raw frames on its standard input."""
    frames = _frames_rgb(figure, draw, count)
    first = next(frames)
    height, width = first.shape[:2]
    command = [shutil.which("ffmpeg"), "-loglevel", "error", "-y", "-f", "rawvideo",
               "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", str(fps), "-i", "-",
               "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
               "-pix_fmt", "yuv420p", "-f", "mp4", str(tmp)]
    with subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE) as ffmpeg:
        try:
            for rgb in itertools.chain([first], frames):
                ffmpeg.stdin.write(rgb.tobytes())
            ffmpeg.stdin.close()
        except BrokenPipeError:  # ffmpeg stopped: its message says why
            pass
        error = ffmpeg.stderr.read().decode(errors="replace").strip()
        if ffmpeg.wait() != 0:
            raise ChainrunError(f"ffmpeg failed: {error.splitlines()[-1] if error else ''}")
