"""``chainrun simulate``: run an experiment file into HDF5 run files."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from chainrun.cli.common import EXIT_BAD_INPUT, EXIT_FAILED_RUNS, fail
from chainrun.errors import ChainrunError, ConfigError


@click.command()
@click.argument("config", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--outdir", type=click.Path(file_okay=False, path_type=Path),
              help="Output folder [default: results/<name>/].")
@click.option("--force", is_flag=True, help="Replace results already in the output folder.")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Runs of a sweep computed at once, in separate processes.")
def simulate(config: Path, outdir: Path | None, force: bool, jobs: int):
    """Run the experiment in CONFIG (YAML or TOML) and write HDF5 run files.

    Each run goes to OUTDIR/<run_id>.h5 (H5MD 1.1: snapshots, contact events,
    final and separation velocities, diagnostics), and OUTDIR/index.h5 lists them
    all. A minimal experiment file:

    \b
      name = "cradle"
      [chain]
      n = 5          # balls
      k = 1          # impacting balls, at velocity 1
      alpha = 1.5    # contact exponent (1 linear, 1.5 Hertz)
      [output]
      times = {start = 0, stop = 20, step = 0.5}
      [sweep]        # optional: every combination is a run
      "chain.k" = [1, 2, 3, 4]

    Optional [solver] keys: t_end (stop time; default: run to the terminal state),
    rtol (accuracy, default 1e-12), max_events.

    \b
    Examples:
      chainrun simulate configs/table1.toml
      chainrun simulate sweep.toml --jobs 2 --force
    """
    from chainrun.config import load_experiment
    from chainrun.runner import simulate_experiment, velocity_table

    try:
        experiment = load_experiment(config)
    except ConfigError as exc:
        for problem in exc.problems:
            click.echo(f"{exc.source}: {problem}", err=True)
        sys.exit(EXIT_BAD_INPUT)
    outdir = outdir if outdir is not None else Path("results") / experiment.name
    runs = experiment.runs()
    click.echo(f"{experiment.name}: {len(runs)} run{'s' * (len(runs) != 1)} -> {outdir}/",
               err=True)
    progress = _Progress(runs) if jobs == 1 else None
    try:
        summaries = simulate_experiment(
            experiment, outdir, force=force, jobs=jobs,
            on_progress=progress.update if progress else None,
            on_run_done=lambda s: (progress and progress.close(), click.echo(s.line())),
        )
    except ChainrunError as exc:
        fail(str(exc))
    except KeyboardInterrupt:
        fail("interrupted; runs not finished were not written", 130)
    table = velocity_table(summaries)
    if table:
        click.echo("\nfinal velocities")
        click.echo(table)
    failed = [s for s in summaries if not s.ok]
    for s in failed:
        click.echo(f"chainrun: run {s.run_id} failed: {s.message}", err=True)
    total = sum(s.wall_time for s in summaries)
    click.echo(f"{len(summaries) - len(failed)} of {len(summaries)} runs finished in "
               f"{total:.2f} s of solver time; index: {outdir / 'index.h5'}", err=True)
    if failed:
        sys.exit(EXIT_FAILED_RUNS)


class _Progress:
    """A progress bar over simulated time, per run, only on a terminal.

    Between output times the bar follows the simulated time up to the last snapshot
    time (or t_end); past it, the run is finishing towards its terminal state.
    """

    def __init__(self, runs):
        self.span = {r.run_id: (r.t_end or (r.times[-1] if len(r.times) else 0.0)) for r in runs}
        self.enabled = sys.stderr.isatty()
        self.bar = None
        self.run_id = None

    def update(self, run_id: str, t: float):
        if not self.enabled:
            return
        if run_id != self.run_id:
            self.close()
            self.run_id = run_id
            self.bar = click.progressbar(length=1000, label=run_id, file=sys.stderr,
                                         show_eta=False)
            self.bar.__enter__()
        span = self.span.get(run_id) or 0.0
        pos = 1000 if span <= 0 else min(1000, int(1000 * t / span))
        self.bar.update(pos - self.bar.pos)

    def close(self):
        if self.bar is not None:
            self.bar.__exit__(None, None, None)
            self.bar = None
            self.run_id = None

