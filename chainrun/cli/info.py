"""``chainrun info``: what a run file holds, read in ten seconds."""

from __future__ import annotations

from pathlib import Path

import click

from chainrun.cli.common import fail
from chainrun.errors import ChainrunError

def _events(counts: dict[str, int]) -> str:
    names = {"OPEN": "openings", "CLOSE": "closings", "RELEASE": "releases",
             "ENGAGE": "engagements", "UNLOAD": "unloadings (a damped force at 0)",
             "RELOAD": "reloadings"}
    total = sum(counts.values())
    parts = [f"{counts[key]} {name}" for key, name in names.items() if counts.get(key)]
    return f"{total} events" + (f" ({', '.join(parts)})" if parts else "")


def render(s) -> str:
    """The summary (``chainrun.analysis.summary.RunSummary``) as lines of text."""
    from chainrun.analysis.summary import law_name
    from chainrun.limits import human_size
    from chainrun.runner import momentum_text

    if s.terminal:
        outcome = f"terminal state at t = {s.end_time:.6g}: no collision can happen again"
    elif s.outcome == "stop_time":
        outcome = f"stopped at t_end = {s.end_time:.6g} (not the terminal state)"
    else:
        outcome = f"FAILED ({s.outcome}): {s.message}"
    share = s.energy
    stored = (f"{s.snapshots} snapshots of positions and velocities, t = "
              f"{s.first_time:.6g} ... {s.last_time:.6g}" if s.snapshots else "no snapshots")
    lines = [
        f"{s.path}  ({human_size(s.file_bytes)}, chainrun {s.creator_version}, {s.created})",
        (f"model     N = {s.n} balls, the first K = {s.k} striking" if s.model else
         f"model     N = {s.n} balls, the first K = {s.k} striking at velocity 1; "
         f"{law_name(s.alpha)} contacts (alpha = {s.alpha:g}); paper units"),
        *([f"line      {s.model}"] if s.model else []),
        f"outcome   {outcome}",
        f"cost      {_events(s.events)}, {s.steps} steps ({s.rejected_steps} rejected), "
        f"at most {s.max_window} balls integrated at once, {s.wall_time:.2f} s",
        *([f"          {s.closed_form} isolated collisions taken whole"]
          if s.closed_form else []),
        f"accuracy  {momentum_text(s.momentum_error)}, |dE|/E = {s.energy_error:.1e} "
        f"(projection corrected {s.energy_correction:.1e} of E); rtol {s.rtol:g}",
        f"balls     fastest: ball {s.fastest[0]} at {s.fastest[1]:.6g}; slowest: ball "
        f"{s.slowest[0]} at {s.slowest[1]:.6g}",
        f"          {s.rebounding} rebound (v < 0), {s.ejected} ejected (v > 1% of the "
        f"impact speed), "
        f"{s.left_behind} left behind",
        *([] if s.model else [  # shares of K/2: the paper's line only
            f"energy    of the impact energy K/2: rebound {share['rebound']:.2%}, ejected "
            f"{share['ejected']:.2%}, left behind {share['left behind']:.2%}, in contacts "
            f"{share['contacts']:.2%}"]),
        *([f"damping   dissipated {s.dissipated:.6g} ({s.dissipated_share:.2%} of the initial "
             f"kinetic energy), most "
             + (f"at contact {s.dissipating}" if s.dissipating else "at a wall")]
          if s.dissipated else []),
        f"stored    {stored}; the event log; final and separation velocities"
        + (f"; forces on {s.sensors} sensor balls at {s.samples} samples" if s.sensors else ""),
    ]
    return "\n".join(lines)


def _row(s) -> str:
    state = f"t = {s.end_time:.6g}" if s.outcome in ("terminal", "stop_time") else s.outcome
    return (f"{Path(s.path).name:<20} {s.n:>8} {s.k:>4} {s.alpha:>6g} {s.outcome:<10} "
            f"{state:<16} {sum(s.events.values()):>8} {s.fastest[1]:>10.6g} "
            f"{s.slowest[1]:>10.6g}")


@click.command()
@click.argument("paths", nargs=-1, required=True,
                type=click.Path(exists=True, path_type=Path))
def info(paths: tuple[Path, ...]):
    """Summarise the run files PATHS, or every run of output folders PATHS.

    For a run file: the model, how the run ended and when, its events, steps and cost,
    its conservation errors, the fastest and slowest balls, how many balls rebound, are
    ejected (moving forward faster than 1% of the impact velocity) or are left behind,
    how the impact energy is shared among them, and what the file stores. For an output
    folder (a sweep, with its index.h5): one line per run, and the full summary when
    the folder holds a single run.

    \b
    Examples:
      chainrun info results/cradle/run.h5
      chainrun info results/table1
    """
    from chainrun.analysis.summary import summarize
    from chainrun.runner import INDEX_NAME
    from chainrun.store import read_index, read_run

    try:
        for i, path in enumerate(paths):
            if i:
                click.echo()
            if path.is_dir():
                index = path / INDEX_NAME
                if not index.is_file():
                    fail(f"{path}: no {INDEX_NAME} (not a chainrun output folder)")
                rows = read_index(index)
                summaries = [summarize(read_run(path / str(r["file"]))) for r in rows]
                if len(summaries) == 1:
                    click.echo(render(summaries[0]))
                    continue
                click.echo(f"{path}: {len(summaries)} runs")
                click.echo(f"{'file':<20} {'N':>8} {'K':>4} {'alpha':>6} {'outcome':<10} "
                           f"{'end':<16} {'events':>8} {'fastest':>10} {'slowest':>10}")
                for s in summaries:
                    click.echo(_row(s))
            else:
                click.echo(render(summarize(read_run(path))))
    except ChainrunError as exc:
        fail(str(exc))
