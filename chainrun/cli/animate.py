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
def animate(run: Path, out: Path, balls: str | None, fps: int):
    """Write a movie of the run file RUN: the balls as discs moving along the line,
    coloured by their velocity, with the time, one frame per snapshot.

    \b
    Examples:
      chainrun animate results/cradle/run.h5 -o cradle.gif
      chainrun animate results/runs/fig05/run.h5 -o wave.mp4 --balls 1:60
    """
    from chainrun.plotting.animate import animate_run

    try:
        path = animate_run(run, out, balls=_ball_range(balls), fps=fps)
    except ChainrunError as exc:
        fail(str(exc))
    click.echo(f"{run}: {path}")
