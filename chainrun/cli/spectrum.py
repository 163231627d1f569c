"""``chainrun spectrum``: the linear spectrum of an experiment's line at rest, to a file
and a figure."""

from __future__ import annotations

import sys
from pathlib import Path

import click
import numpy as np

from chainrun.cli.common import EXIT_BAD_INPUT, fail
from chainrun.errors import ChainrunError, ConfigError


def _value(x: float, quantity: str, units: str) -> str:
    """A frequency to four significant digits, trailing zeros kept so that every number
    shows the same precision (26.40 krad/s beside 45.02 krad/s); 0 exactly as 0."""
    from chainrun.units import format_value

    return format_value(0.0 if x == 0.0 else x, quantity, units, zeros=x != 0.0)


def _range(values, quantity: str, units: str) -> str:
    low, high = (_value(float(v), quantity, units) for v in (min(values), max(values)))
    return low if low == high else f"{low} ... {high}"


def summary(ds) -> list[str]:
    """A spectrum Dataset in a few lines: the modes, the bands and their gaps."""
    units = "si" if ds.attrs.get("units") == "SI" else "paper"
    omega, f = ds["omega"].values, ds["frequency"].values
    left_out = int(ds.attrs.get("strikers_left_out", 0))
    balls = ds["ball"].size
    lines = [f"N = {balls} ball{'s' * (balls != 1)} at rest"
             + (f" ({left_out} striker{'s' * (left_out != 1)} left out)" if left_out else "")
             + f", {omega.size} mode{'s' * (omega.size != 1)}: omega "
             f"{_range(omega, 'angular_frequency', units)} (f {_range(f, 'frequency', units)})"]
    zero = int(ds.attrs.get("zero_modes", 0))
    if zero == omega.size:
        lines.append("  no contact carries a load: every mode has zero frequency (an "
                     "unloaded contact with alpha > 1 has no linear stiffness; "
                     "chain.precompression loads the line)")
    elif zero:
        lines.append(f"  {zero} mode{'s' * (zero != 1)} of zero frequency: pieces of the "
                     "line that no loaded contact ties to a wall move freely")
    if "band_bottom" in ds:
        bottom, top = ds["band_bottom"].values, ds["band_top"].values
        period = int(ds.attrs["period"])

        def between(a: float, b: float) -> str:
            """omega from a to b, and f (the drives' frequency) in brackets."""
            turn = 2.0 * np.pi
            return (f"{_value(a, 'angular_frequency', units)} ... "
                    f"{_value(b, 'angular_frequency', units)} (f "
                    f"{_value(a / turn, 'frequency', units)} ... "
                    f"{_value(b / turn, 'frequency', units)})")

        bands = "; ".join(between(float(a), float(b)) for a, b in zip(bottom, top))
        lines.append(f"  periodic, {period} ball{'s' * (period != 1)} per cell; pass "
                     f"band{'s' * (period != 1)} (omega): {bands}")
        gaps = [between(float(top[b]), float(bottom[b + 1]))
                for b in range(bottom.size - 1) if bottom[b + 1] > top[b]]
        cut = float(top[-1])
        lines.append(f"  band gap{'s' * (len(gaps) != 1)}: {'; '.join(gaps)}" if gaps
                     else f"  cut-off: {_value(cut, 'angular_frequency', units)} (f "
                     f"{_value(cut / (2.0 * np.pi), 'frequency', units)}; no gap "
                     "below it)")
    return lines


def _numbers_hash(ds) -> str:
    """sha256 of a spectrum's numbers (its variables and coordinates, not its
    attributes, which name the run)."""
    import hashlib

    h = hashlib.sha256()
    for name in sorted(ds.variables):
        h.update(name.encode() + b"\0" + np.ascontiguousarray(ds[name].values).tobytes())
    return h.hexdigest()


@click.command()
@click.argument("config", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--outdir", type=click.Path(file_okay=False, path_type=Path),
              help="Output folder [default: results/<name>/spectrum/].")
@click.option("--period", type=click.IntRange(min=0), default=None,
              help="Balls in the unit cell of the dispersion relation [default: the "
                   "smallest cell the line repeats at least twice]; 0 for none.")
def spectrum(config: Path, outdir: Path | None, period: int | None):
    """The linear spectrum of the line in CONFIG, at rest in its static state.

    The line is the one `chainrun simulate` would run, its strikers left out, about
    its static state: chain.precompression = F0 holds it against a right wall or,
    with both walls and k = 0, loads every contact with F0 between them. Each
    contact's linear stiffness is alpha kappa delta0^(alpha - 1) (a touching linear
    contact: kappa; an unloaded Hertz contact: 0), and the normal modes solve
    K x = omega^2 M x. A line that repeats a unit cell of balls also gets the
    dispersion relation omega(q) of the infinite line, its band edges and gaps.
    Nothing is run: a line held between two walls needs no solver.t_end here.

    Each run goes to OUTDIR/<run_id>.h5 (an xarray Dataset as netCDF-4: omega and
    frequency per mode, ascending, in the inverse of the file's time unit; the mode
    shapes; the contacts' static compression, force and linear stiffness; for a
    periodic line the dispersion and band edges) and its figure to
    OUTDIR/<run_id>.png and .pdf; a run of a sweep whose line at rest is an earlier
    run's (a sweep of its drive) is said to be, and written once. chainrun.spectrum(...)
    gives the same Dataset in Python.

    \b
    Examples:
      chainrun spectrum configs/examples/granular-crystal.toml
      chainrun spectrum crystal.toml -o results/crystal-spectrum --period 2
    """
    from chainrun.analysis.spectrum import run_spectrum
    from chainrun.config import load_experiment
    from chainrun.paths import spectrum_dir
    from chainrun.plotting import render_spectrum
    from chainrun.store import write_spectrum

    try:
        experiment = load_experiment(config, to_run=False)
    except ConfigError as exc:
        for problem in exc.problems:
            click.echo(f"{exc.source}: {problem}", err=True)
        sys.exit(EXIT_BAD_INPUT)
    outdir = outdir if outdir is not None else spectrum_dir(experiment.name)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        fail(f"{outdir}: cannot create the output folder ({exc.strerror})")
    written: dict[str, tuple[str, Path]] = {}  # the numbers' hash: the first run, its file
    for spec in experiment.runs(to_run=False):
        where = f"{config}: " + (f"run {spec.run_id}: " if experiment.sweep else "")
        try:
            ds = run_spectrum(spec, period=period)
            same = written.get(_numbers_hash(ds))
            if same is not None:  # (a sweep of what drives the line, not of the line)
                click.echo(f"{spec.run_id}: the same line at rest as {same[0]}, the same "
                           f"spectrum: {same[1]}")
                continue
            path = outdir / f"{spec.run_id}.h5"
            written[_numbers_hash(ds)] = (spec.run_id, path)
            write_spectrum(path, ds)
            figures = render_spectrum(path, out=outdir)
        except ConfigError as exc:  # the line's values, checked as it is built
            fail(f"{where}{'; '.join(exc.problems)}")
        except ChainrunError as exc:
            fail(f"{where}{exc}")
        click.echo(f"{spec.run_id}: " + "\n".join(summary(ds)))
        click.echo(f"  -> {path}, {', '.join(p.name for p in figures)}")
