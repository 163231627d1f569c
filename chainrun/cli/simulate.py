"""``chainrun simulate``: run an experiment file into HDF5 run files."""

from __future__ import annotations

import shutil
import sys
import time
from pathlib import Path

import click

from chainrun.cli.common import EXIT_BAD_INPUT, EXIT_FAILED_RUNS, EXIT_INTERRUPTED, fail
from chainrun.errors import ChainrunError, ConfigError



@click.command()
@click.argument("config", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--outdir", type=click.Path(file_okay=False, path_type=Path),
              help="Output folder [default: results/<name>/].")
@click.option("--force", is_flag=True,
              help="Replace run files computed from another config. Runs whose file "
                   "matches the config are skipped, with or without --force.")
@click.option("--check", is_flag=True,
              help="Run each line a second time at a tenth of its rtol and store the "
                   "spread of every ball's final and separation velocities "
                   "(results/final_velocity_spread); the summary says how many balls "
                   "hold to 1e-9 of the impact speed (a driven line at rest: of "
                   "its wall's speed 2 pi f A). As solver.check = true.")
@click.option("--check-outdir", type=click.Path(file_okay=False, path_type=Path),
              help="With the check, also write each check run's own run file (and an "
                   "index) into this folder, so that any number derived from the runs "
                   "can be computed from both; implies --check.")
@click.option("-j", "--jobs", type=click.IntRange(min=1), default=None,
              help="Runs computed at once on this machine [default: 1, in this "
                   "process]; more start a local Dask cluster (local processes "
                   "without Dask).")
@click.option("--scheduler", metavar="ADDRESS",
              help="Run on an existing Dask cluster, e.g. tcp://10.0.0.5:8786 "
                   "[default: $DASK_SCHEDULER_ADDRESS if set and --jobs is not given].")
@click.option("--scheduler-file", type=click.Path(dir_okay=False, path_type=Path),
              help="Run on the Dask cluster described by this file "
                   "(dask scheduler --scheduler-file).")
def simulate(config: Path, outdir: Path | None, force: bool, check: bool,
             check_outdir: Path | None, jobs: int | None, scheduler: str | None,
             scheduler_file: Path | None):
    """Run the experiment in CONFIG (YAML or TOML) and write HDF5 run files.

    Each run goes to OUTDIR/<run_id>.h5 (H5MD 1.1: snapshots, contact events,
    final and separation velocities, diagnostics), and OUTDIR/index.h5 lists them
    all. Two minimal experiment files, real beads in SI and the paper's line in its
    units (every coefficient 1):

    \b
      name = "beads"
      units = "si"
      [chain]
      n = 30
      k = 1                  # striking balls, at chain.speed
      speed = 0.5            # m/s
      diameter = 0.008       # m: masses and Hertz contacts from the material
      material = "stainless_steel"
      [output]
      times = {start = 0, stop = 3e-4, step = 2e-6}      # s
      sensors = [10, 20]     # force sensors: chainrun info gives their pulses
      sensor_dt = 2e-7

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

    Any line: [chain] mass, force, velocity (per ball), stiffness, alpha, gap (per
    contact) each take a number, a list, or a generator table: {pattern = [1, 0.5]},
    {taper = 0.9, start = 1}, {random = "uniform", low = 0.5, high = 2, seed = 1}
    (or "lognormal" with median, sigma), {value = 1, impurity = {at = 20, value =
    0.1}} (at counts from 1), {file = "m.npy"} (or .csv, beside CONFIG). chain.k
    and chain.speed set the first k balls moving (k = 0: a line at rest);
    chain.precompression = F0 holds the resting balls against a right wall, or,
    with both walls and k = 0, loads every contact with F0 between them (the left
    wall placed so); chain.gravity = g weighs every ball towards ball N, a column
    resting on its right wall. [walls.left] and [walls.right] take
    stiffness, alpha, gap. units = "si" adds per-ball diameter (m) and material
    (steel, stainless_steel, chrome_steel, brass, aluminium, glass, ptfe,
    tungsten_carbide; or young, poisson, density): masses and Hertz contacts follow,
    and a wall may have a material. Driven lines: walls.left.motion = {amplitude,
    frequency, ramp} moves a wall about its place by A r(t/T) sin(2 pi f t) (a list
    of tables: their sum; {file = "drive.csv"}: times and displacements, a cubic
    spline held after the last time), and chain.drive = [{ball, amplitude,
    frequency, ramp}] (or {ball, file}) puts forces of the same forms on balls. A
    line with a constant force, a drive or two walls needs solver.t_end.
    Dissipation, per contact: damping (eta) and damping_exponent
    (beta), F = max(0, k d^alpha + eta d^beta d'), or restitution (0 < e <= 1) with
    damping_law ("dashpot", "kuwabara-kono", "tsuji") and, where e depends on the
    impact speed, restitution_speed; the walls take the same keys. docs/guide.md
    has every key.

    Optional [solver] keys: t_end (stop time; default: run to the terminal state),
    rtol (accuracy, default 1e-12), max_events, check (true: as --check). Optional
    [output] keys besides
    times: sensors (ball numbers) and sensor_dt, to sample the contact forces on
    those balls every sensor_dt, up to sensor_end (default: t_end, else the last
    snapshot time).

    Ensembles: a [sweep] may vary a generator table's numeric key, such as
    "chain.mass.seed" = [1, 2, 3], or ask for replicas = 8 (each random table's seed
    moved on by 0..7); `chainrun info OUTDIR` gives their statistics, `chainrun plot
    OUTDIR` their mean and spread, chainrun.open_sweep(OUTDIR) one Dataset.

    Which digits hold: --check (or solver.check = true) runs each line again at a
    tenth of its rtol (ten times it where a tenth is below 1e-15) and stores each
    ball's spread, |v(rtol) - v(check rtol)|; a ball holds when its spreads are at
    most 1e-9 of the impact speed (of the drive's speed, 2 pi f A, on a driven line at
    rest). A clean line holds on every ball; a cascade or a
    disordered line may not, and its summary line says so. It doubles the solver's
    time.

    Sweeps resume: a run whose file already holds the same config is skipped, so
    after an interruption the same command computes only what is missing. A file
    of another config stops the command unless --force is given. A failed run does
    not stop the others; all failures are listed at the end (exit status 1; 2 for bad
    input; 130 when interrupted, Ctrl-C).

    \b
    Examples:
      chainrun simulate configs/table1.toml
      chainrun simulate configs/examples/newtons-cradle.toml
      chainrun simulate sweep.toml --jobs 4
      chainrun simulate sweep.toml --force          # the config changed
      chainrun simulate disorder.toml --check       # which digits hold
      chainrun simulate sweep.toml --scheduler tcp://10.0.0.5:8786
    """
    from chainrun._gc import start_up

    with start_up("simulate"):  # pydantic and the config models
        from chainrun.config import load_experiment
        from chainrun.check import energy_doubt
        from chainrun.cli.text import run_line, velocity_table
        from chainrun.paths import outdir as default_outdir
        from chainrun.runner import simulate_experiment

        try:
            experiment = load_experiment(config)
        except ConfigError as exc:
            for problem in exc.problems:
                click.echo(f"{exc.source}: {problem}", err=True)
            sys.exit(EXIT_BAD_INPUT)
    outdir = outdir if outdir is not None else default_outdir(experiment.name)
    total = len(experiment.runs())
    click.echo(f"{experiment.name}: {total} run{'s' * (total != 1)} -> {outdir}/", err=True)
    bar = _SweepBar()

    def run_done(run):
        bar.clear()
        click.echo(run_line(run))
        doubt = getattr(run, "ok", False) and energy_doubt(run.energy_error,
                                                           run.energy_floor)
        if doubt:
            click.echo(f"chainrun: warning: {run.run_id}: {doubt}", err=True)

    try:
        try:
            result = simulate_experiment(
                experiment, outdir, force=force, check=check, check_outdir=check_outdir,
                jobs=jobs, scheduler=scheduler,
                scheduler_file=scheduler_file, on_progress=bar.run_time,
                on_run_done=run_done, on_update=bar.update,
                on_warning=lambda w: click.echo(f"chainrun: warning: {w}", err=True),
            )
        finally:
            bar.clear()
    except ChainrunError as exc:
        fail(str(exc))
    except KeyboardInterrupt:
        fail("interrupted; " + ("finished runs are kept: the same command resumes the sweep"
                                if total > 1 else "no run file was written: the same command "
                                "runs it again"), EXIT_INTERRUPTED)
    table = velocity_table(result.summaries)
    if table:
        click.echo("\n" + table)
    for run in result.failures:
        click.echo(f"chainrun: run {run.run_id} failed: {run.message}", err=True)
    computed = [r for r in result.computed if r.ok]
    skipped = [r for r in result.skipped if r.ok]
    solver_time = sum(r.wall_time for r in computed)
    check_time = sum(r.check.wall_time for r in computed if r.check is not None)
    checks = f", {check_time:.2f} s more for the checks" if check_time else ""
    where = f" {result.workers}" if result.workers else ""
    click.echo(f"{total} run{'s' * (total != 1)}: {len(computed)} computed{where} "
               f"({solver_time:.2f} s of solver time{checks}), {len(skipped)} skipped, "
               f"{len(result.failures)} failed; index: {outdir / result.index.name}", err=True)
    if result.failures:
        sys.exit(EXIT_FAILED_RUNS)


class _SweepBar:
    """One progress line over the sweep on stderr, drawn only on a terminal.

    ``[#####.....] 12/40 done 8, running 2, failed 1, skipped 3; 0:42 k=2 t = 12.5``
    (counts of zero left out; a single run shows only its clock and its simulated
    time, which is what moves). On a narrow terminal the bar goes first, then the
    counts, then the count of runs finished, so that the time stays.

    Redrawn at most ten times a second, and only when the line changes.
    """

    WIDTH = 20

    def __init__(self):
        self.enabled = sys.stderr.isatty()
        self.counts = None
        self.current = ""
        self.shown = False
        self.drawn_at = 0.0
        self.line = ""
        self.started = time.monotonic()

    def update(self, counts) -> None:
        self.counts = counts
        if not counts.current:
            self.current = ""
        self.draw()

    def run_time(self, run_id: str, t: float) -> None:
        """Simulated time of a run computed in this process."""
        self.current = f"{run_id} t = {t:.4g}"
        self.draw()

    def draw(self) -> None:
        if not self.enabled or self.counts is None:
            return
        now = time.monotonic()
        if self.shown and now - self.drawn_at < 0.1:
            return
        self.drawn_at = now
        line = self.text(self.counts, self.current, now - self.started,
                         shutil.get_terminal_size().columns - 1)
        if self.shown and line == self.line:
            return
        self.line = line
        sys.stderr.write("\r\x1b[K" + line)
        sys.stderr.flush()
        self.shown = True

    @classmethod
    def text(cls, c, current: str, elapsed: float, columns: int) -> str:
        """The line for counts ``c``, within ``columns`` characters."""
        minutes, seconds = divmod(int(elapsed), 60)
        tail = f"{minutes}:{seconds:02d}"
        current = current or c.current
        if current:
            tail += f" {current}"
        if c.total == 1:
            return tail[:columns]
        filled = cls.WIDTH * c.finished // max(c.total, 1)
        bar = f"[{'#' * filled}{'.' * (cls.WIDTH - filled)}] "
        counts = [f"done {c.done}", f"running {c.running}"] + [
            f"{name} {n}" for name, n in (("failed", c.failed), ("skipped", c.skipped)) if n]
        for line in (f"{bar}{c.finished}/{c.total} {', '.join(counts)}; {tail}",
                     f"{c.finished}/{c.total} {', '.join(counts)}; {tail}",
                     f"{c.finished}/{c.total}; {tail}", tail):
            if len(line) <= columns:
                return line
        return line[:columns]

    def clear(self) -> None:
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()
            self.shown = False
