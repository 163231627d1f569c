"""``chainrun plot``: draw figures and tables from analysis files, or list the artefacts."""

from __future__ import annotations

import json
import os
from pathlib import Path

import click

from chainrun.cli.common import fail
from chainrun.errors import ChainrunError
from chainrun.paths import INDEX_NAME, RESULTS, index_file


def _ensemble(folder: Path):
    """The statistics of the runs in ``folder`` if they are an ensemble, else None."""
    from chainrun.analysis.ensemble import ensemble, is_ensemble
    from chainrun.store import read_index, read_run

    runs = [read_run(folder / str(row["file"])) for row in read_index(index_file(folder))]
    return ensemble(runs) if is_ensemble(runs) else None


def _transmission(folder: Path):
    """The transmission curve of the runs in ``folder`` if they sweep a wall's drive
    frequency and have force sensors, else None."""
    from chainrun.analysis.transmission import measure_sweep
    from chainrun.store import read_index, read_run

    runs = [read_run(folder / str(row["file"])) for row in read_index(index_file(folder))]
    swept = any(key.startswith("walls.") and key.endswith(".motion.frequency")
                for run in runs for key in run.parameters.get("overrides", {}))
    if not swept or not all(run.sensor_balls.size for run in runs):
        return None
    return measure_sweep(runs)


def _pulses(folder: Path):
    """The pulses of the runs in ``folder`` against their swept key
    (``chainrun.analysis.pulse_sweep.PulseSweep``) where they sweep one key and their
    struck lines carry force sensors (an ensemble over seeds is drawn by its
    statistics), else None."""
    from chainrun.analysis.ensemble import is_ensemble
    from chainrun.analysis.pulse import measure_pulses, pulsed
    from chainrun.analysis.pulse_sweep import pulse_sweep
    from chainrun.store import read_index, read_run

    runs = [read_run(folder / str(row["file"])) for row in read_index(index_file(folder))]
    keys = {key for run in runs for key in run.parameters.get("overrides", {})}
    if len(keys) != 1 or is_ensemble(runs) or not all(pulsed(run) for run in runs):
        return None
    return pulse_sweep(runs, [measure_pulses(run) for run in runs], keys.pop())


def _draw_run(args):
    from chainrun.plotting import render_run

    path, views, out, log = args
    return path, render_run(path, views, out=out, log=log)


def _each_run(files, views, out, log):
    """(run file, files drawn) for each of ``files`` in order: the runs' views drawn on
    as many processes as there are cores (a sweep's runs are independent figures)."""
    import multiprocessing

    tasks = [(path, views, out, log) for path in files]
    workers = min(len(tasks), os.cpu_count() or 1, MAX_PLOT_WORKERS)
    # (forked: the workers start with this process's imports, and draw in its style;
    # where a system cannot fork, the runs are drawn here, one after another)
    if workers <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        yield from map(_draw_run, tasks)
        return
    import concurrent.futures as cf

    with cf.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
        yield from pool.map(_draw_run, tasks)


#: The most processes ``chainrun plot`` draws a sweep's runs on.
MAX_PLOT_WORKERS = 8


@click.command()
@click.argument("names", nargs=-1)
@click.option("--all", "all_", is_flag=True,
              help="Every artefact with outputs, in the registry's order.")
@click.option("--list", "list_", is_flag=True,
              help="List the artefacts (name, kind, inputs, outputs) and exit.")
@click.option("--format", "format_", type=click.Choice(["text", "json", "make"]),
              default="text", show_default=True,
              help="Format of --list; `make` writes the rules the Makefile includes.")
@click.option("-r", "--results", type=click.Path(file_okay=False, path_type=Path),
              default=RESULTS, show_default=True,
              help="Results folder: analysis files are read from RESULTS/analysis/, outputs "
                   "written under RESULTS/.")
@click.option("--what", default=None, metavar="VIEWS",
              help="For a run file or folder: the views to draw, comma-separated: spacetime "
                   "(velocity over ball and time), forces (contact force over contact and "
                   "time), profiles and displacements (along the line at some snapshot "
                   "times), final (final velocity of each ball), energy, sensors (the force "
                   "sensors' traces); for a sweep's folder also sweep-final, sweep-runs, "
                   "sweep-pulses, ensemble, transmission (naming only these draws no "
                   "run's own views; naming none, the sweep's own are drawn too) "
                   "[default: every view the runs have data for].")
@click.option("--log", is_flag=True,
              help="For a run file or folder: final velocities on a (symmetric) log scale.")
@click.option("--balls", default="1,-1", show_default=True, metavar="NUMBERS",
              help="For an output folder of a sweep: the balls whose final velocities are "
                   "drawn against each swept key (sweep-final.png), comma-separated, "
                   "negative from the end (-1: the last ball).")
@click.option("-o", "--out", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="For a run file or folder: where the views go (default: a figures/ "
                   "folder beside each run file).")
def plot(names: tuple[str, ...], all_: bool, list_: bool, format_: str, results: Path,
         what: str, log: bool, balls: str, out: Path | None):
    """Draw the figures and tables NAMES from their analysis files, or the standard
    views of run files and output folders NAMES.

    A NAME that is a run file (or an output folder of run files) gets its views,
    drawn from the file alone: space-time diagrams of the velocity and of the contact
    forces, velocity and displacement profiles at snapshot times, the final
    velocities, the energy over time and the force sensors' traces, each as PNG and
    PDF (--what picks them); an output folder of a sweep also gets its final
    velocities against each swept key (sweep-final.png, --balls picks the balls) and
    a panel per run (sweep-runs.png), or for an ensemble over seeds their mean and
    spread (ensemble.png); a sweep of one key whose struck lines carry force sensors
    also gets their pulses' wave speed, peak force and width against it, with the
    power laws fitted through them (sweep-pulses.png); a sweep of a wall's drive
    frequency with force sensors gets its transmission curve against the line's bands
    instead (transmission.png, `chainrun.transmission`): where a driven run stops, its
    velocities are a snapshot of its oscillation.

    Figures go to RESULTS/figures/figNN.png and .pdf, Table 1 to
    RESULTS/tables/table1.md and .csv, and the comparison of every printed number to
    RESULTS/paper-comparison.csv and .md. Nothing is computed here: each output is
    drawn from RESULTS/analysis/<name>.h5 (`chainrun analyze`). The same inputs give
    the same bytes.

    \b
    Examples:
      chainrun plot results/cradle/run.h5            # -> results/cradle/figures/
      chainrun plot results/table1 --what final --log --balls 1,2,-1
      chainrun plot results/driven-dimer             # + transmission.png
      chainrun plot results/driven-dimer --what transmission   # that figure alone
      chainrun plot --list
      chainrun plot fig05
      chainrun plot --all
      chainrun plot --list --format make > results/artefacts.mk
    """
    from chainrun import artefacts

    if list_:
        if format_ == "make":
            click.echo(artefacts.make_rules(results=str(results)), nl=False)
        elif format_ == "json":
            rows = [dict(name=a.name, kind=a.kind, title=a.title,
                         experiments=list(a.experiments), needs=list(a.needs),
                         outputs=[str(p) for p in artefacts.output_paths(a, results)])
                    for a in artefacts.ALL]
            click.echo(json.dumps(rows, indent=2))
        else:
            for a in artefacts.ALL:
                outputs = ", ".join(str(p) for p in artefacts.output_paths(a, results))
                click.echo(f"{a.name:17s} {a.kind:10s} {a.title}")
                inputs = ", ".join([f"configs/{e}.toml" for e in a.experiments] + list(a.needs))
                click.echo(f"{'':28s}from: {inputs}")
                click.echo(f"{'':28s}to:   {outputs or artefacts.analysis_path(a.name, results)}")
        return
    from chainrun.plotting import SWEEP_VIEWS, render, render_run, render_sweep

    known = {a.name for a in artefacts.ALL}
    if names and all(name not in known and Path(name).exists() for name in names):
        views = None if what is None else [v.strip() for v in what.split(",") if v.strip()]
        sweep_views = None if views is None else [v for v in views if v in SWEEP_VIEWS]
        run_views = None if views is None else [v for v in views if v not in SWEEP_VIEWS]
        try:
            numbers = [int(b) for b in balls.split(",") if b.strip()]
        except ValueError:
            fail(f"--balls {balls!r}: expected ball numbers, e.g. 1,-1")
        for name in names:
            folder = Path(name)
            files = sorted(p for p in folder.glob("*.h5") if p.name != INDEX_NAME) \
                if folder.is_dir() else [folder]
            if not files:
                fail(f"{name}: no run files")
            sweep = folder.is_dir() and len(files) > 1 and index_file(folder).is_file()
            if sweep_views and not sweep:
                fail(f"{name}: {', '.join(sweep_views)}: views of a sweep's folder, and "
                     "this is not one")
            try:
                # naming only a sweep's views draws no run's own
                only_sweep = views is not None and not run_views
                drawn = _each_run([] if only_sweep else files, run_views, out, log)
                for path, paths in drawn:
                    click.echo(f"{path}: {', '.join(str(p) for p in paths)}")
                if sweep:
                    paths = render_sweep(folder, numbers, out=out, log=log,
                                         ensemble=_ensemble(folder),
                                         transmission=_transmission(folder),
                                         pulses=_pulses(folder),
                                         views=sweep_views or None)
                    click.echo(f"{folder}: {', '.join(str(p) for p in paths)}")
            except ChainrunError as exc:
                fail(str(exc))
        return
    for name in names:
        if name not in known and (name.endswith(".h5") or "/" in name) and not Path(name).exists():
            fail(f"{name}: no such file or folder")
    if all_:
        names = tuple(a.name for a in artefacts.ARTEFACTS if a.plot is not None)
    if not names:
        fail("name at least one artefact, or give --all or --list")
    for name in names:
        try:
            paths = render(name, results=results)
        except ChainrunError as exc:
            fail(str(exc))
        click.echo(f"{name}: {', '.join(str(p) for p in paths)}")
