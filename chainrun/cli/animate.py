"""``chainrun animate``: a movie of a run, the balls moving along the line."""

from __future__ import annotations

from pathlib import Path

import click

from chainrun.cli.common import fail
from chainrun.errors import ChainrunError


def _ball_range(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        first, last = (int(part) for part in text.split(":"))
    except ValueError:
        fail(f"--balls {text!r}: expected FIRST:LAST, e.g. 1:50")
    return first, last


@click.command()
@click.argument("run", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The movie: .gif (written without any external program) or .mp4 "
                   "(needs ffmpeg).")
@click.option("--balls", metavar="FIRST:LAST", default=None,
              help="The balls shown, 1-based and inclusive (default: all, at most the "
                   "first 300).")
@click.option("--fps", type=click.IntRange(1, 120), default=20, show_default=True,
              help="Frames per second; a frame per snapshot (at most 400 frames).")
@click.option("--magnify", type=float, default=None, metavar="FACTOR",
              help="Draw displacements and gaps FACTOR times their size (default: the "
                   "largest 1, 2 or 5 times a power of ten that shows the largest "
                   "compression as at most a quarter of a diameter and keeps the "
                   "magnified motion within the line's length).")
@click.option("--width", type=click.IntRange(320, 3840), default=800, show_default=True,
              metavar="PIXELS", help="The frames' width in pixels; their height (a "
                                     "third of it) and text scale with it.")
def animate(run: Path, out: Path, balls: str | None, fps: int, magnify: float | None,
            width: int):
    """Write a movie of the run file RUN: the balls moving along the line, coloured by
    their velocity, one frame per snapshot, with the time in the run's units.

    Real spheres (an SI run with diameters) are drawn to scale along the line, their
    displacements and gaps magnified by a factor written on each frame, so that pressed
    balls overlap by their magnified compression; walls are drawn as hatched bars. A
    line without diameters (the paper's) is a schematic: ball n at place n, 1 wide.

    \b
    Examples:
      chainrun animate results/cradle/run.h5 -o cradle.gif
      chainrun animate results/steel/run.h5 -o steel.gif --magnify 1000
      chainrun animate results/runs/fig05/run.h5 -o wave.mp4 --balls 1:60
      chainrun animate results/steel/run.h5 -o steel.gif --width 1600
    """
    from chainrun.plotting.animate import animate_run

    try:
        path = animate_run(run, out, balls=_ball_range(balls), fps=fps, magnify=magnify,
                           width=width)
    except ChainrunError as exc:
        fail(str(exc))
    click.echo(f"{run}: {path}")
