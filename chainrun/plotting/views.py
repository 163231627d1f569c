"""Standard views of any run file, drawn from what the file stores and nothing else.

``VIEWS`` names them: ``spacetime`` (velocity over ball and time, an image in which the
wave front shows), ``forces`` (contact force over contact and time), ``profiles`` and
``displacements`` (velocity and displacement along the line at some snapshot times),
``final`` (final velocity of every ball), ``energy`` (kinetic, contact and total energy
over time) and ``sensors`` (the force sensors' traces). ``draw_sweep`` draws a sweep's
final velocities against its swept keys, ``draw_sweep_runs`` a panel per run. Each artist carries a ``gid`` naming the array it shows, so tests can match what
is drawn with the file.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from chainrun.errors import ChainrunError
from chainrun.plotting.common import MARKERS

__all__ = ["VIEWS", "draw_sweep", "draw_sweep_runs", "draw_view"]

VIEWS = ("spacetime", "forces", "profiles", "displacements", "final", "energy", "sensors")
#: an image wider than this many balls shows every s-th ball (the file is read so)
MAX_IMAGE_BALLS = 2000
#: profiles drawn at most
MAX_PROFILES = 6
UNITS = "paper units"


def _snapshots_needed(run, view: str, least: int) -> None:
    if run.times.size < least:
        raise ChainrunError(f"{run.path}: {view} needs at least {least} snapshots, the file "
                            f"has {run.times.size} (set output.times in the experiment)")


def _spacetime(run, figure: Figure, axes) -> None:
    _snapshots_needed(run, "spacetime", 2)
    stride = -(-run.n // MAX_IMAGE_BALLS)
    v = np.asarray(run.velocities[:, ::stride])
    balls = np.arange(1, run.n + 1)[::stride]
    top = float(np.max(np.abs(v))) or 1.0
    image = axes.imshow(v.T, origin="lower", aspect="auto", cmap="RdBu_r",
                        vmin=-top, vmax=top, interpolation="nearest",
                        extent=(run.times[0], run.times[-1], balls[0] - 0.5,
                                balls[-1] + stride - 0.5), gid="velocity")
    figure.colorbar(image, ax=axes, label=f"velocity ({UNITS})")
    axes.set_xlabel(f"time ({UNITS})")
    axes.set_ylabel("ball" + (f" (every {stride}th)" if stride > 1 else ""))


def _forces(run, figure: Figure, axes) -> None:
    _snapshots_needed(run, "forces", 2)
    if run.n < 2:
        raise ChainrunError(f"{run.path}: a line of one ball has no contacts")
    stride = -(-(run.n - 1) // MAX_IMAGE_BALLS)
    force = run.contact_forces(stride)
    contacts = np.arange(1, run.n)[::stride]
    image = axes.imshow(force.T, origin="lower", aspect="auto", cmap="magma_r",
                        vmin=0.0, interpolation="nearest",
                        extent=(run.times[0], run.times[-1], contacts[0] - 0.5,
                                contacts[-1] + stride - 0.5), gid="force")
    figure.colorbar(image, ax=axes, label=f"contact force ({UNITS})")
    axes.set_xlabel(f"time ({UNITS})")
    axes.set_ylabel("contact j (balls j, j+1)" + (f", every {stride}th" if stride > 1 else ""))


def _along_the_line(run, figure: Figure, axes, name: str, data, label: str) -> None:
    _snapshots_needed(run, name, 1)
    picks = np.unique(np.linspace(0, run.times.size - 1, MAX_PROFILES).round().astype(int))
    balls = np.arange(1, run.n + 1)
    for i in picks:
        axes.plot(balls, data[i], label=f"t = {run.times[i]:.4g}", gid=f"{name}/{i}")
    axes.set_xlabel("ball")
    axes.set_ylabel(f"{label} ({UNITS})")
    axes.legend(fontsize="small")


def _profiles(run, figure: Figure, axes) -> None:
    _along_the_line(run, figure, axes, "velocity", run.velocities, "velocity")


def _displacements(run, figure: Figure, axes) -> None:
    _along_the_line(run, figure, axes, "displacement", run.positions, "displacement")


def _sensors(run, figure: Figure, axes) -> None:
    if run.sensor_balls.size == 0:
        raise ChainrunError(f"{run.path}: no force sensors (set output.sensors and "
                            "output.sensor_dt in the experiment)")
    for s, ball in enumerate(run.sensor_balls):
        axes.plot(run.sensor_time, run.sensor_force[:, s, :].mean(axis=1),
                  label=f"ball {ball}", gid=f"sensor/{ball}")
    axes.set_xlabel(f"time ({UNITS})")
    axes.set_ylabel(f"mean contact force on the ball ({UNITS})")
    axes.legend(fontsize="small")


def _final(run, figure: Figure, axes, log: bool) -> None:
    v = run.final_velocity
    axes.plot(np.arange(1, run.n + 1), v, marker="o", markersize=3, color="black",
              gid="final_velocity")
    axes.axhline(0.0, color="0.6", linewidth=0.6)
    axes.set_xlabel("ball")
    axes.set_ylabel(f"final velocity ({UNITS})")
    if log:
        small = np.abs(v[v != 0.0])
        axes.set_yscale("symlog", linthresh=max(float(small.min()) if small.size else 1.0,
                                                1e-12))


def _energy(run, figure: Figure, axes) -> None:
    _snapshots_needed(run, "energy", 2)
    t = run.times
    kinetic = run.observables["kinetic_energy"]
    stored = run.observables["potential_energy"]
    axes.plot(t, kinetic, label="kinetic", gid="kinetic_energy")
    axes.plot(t, stored, label="in contacts", gid="potential_energy")
    axes.plot(t, kinetic + stored, label="total", color="black", gid="total_energy")
    axes.set_xlabel(f"time ({UNITS})")
    axes.set_ylabel(f"energy ({UNITS})")
    axes.legend(fontsize="small")


def draw_view(run, view: str, *, log: bool = False) -> Figure:
    """The Figure of ``view`` (one of ``VIEWS``) for a run (``chainrun.store.RunData``).

    ``log`` draws the final velocities on a symmetric log scale (linear below the
    smallest non-zero magnitude). Must be called inside ``chainrun.plotting.style()``
    for the figure to look as saved.
    """
    if view not in VIEWS:
        raise ChainrunError(f"no view {view!r} (the views: {', '.join(VIEWS)})")
    figure = Figure()
    axes = figure.add_subplot()
    if view == "final":
        _final(run, figure, axes, log)
    else:
        {"spacetime": _spacetime, "forces": _forces, "profiles": _profiles,
         "displacements": _displacements, "energy": _energy, "sensors": _sensors}[view](
            run, figure, axes)
    experiment = run.parameters.get("experiment", "")
    run_id = run.parameters.get("run_id", "")
    axes.set_title(f"{experiment} {run_id}: N = {run.n}, K = {run.k}, "
                   f"alpha = {run.alpha:g}", fontsize="medium")
    return figure


def _ball_index(ball: int, n: int) -> int | None:
    """0-based index of ball number ``ball`` (negative: from the end) in a line of n."""
    i = ball - 1 if ball > 0 else n + ball
    return i if 0 <= i < n else None


def draw_sweep(runs, balls=(1, -1)) -> Figure:
    """Final velocities of ``balls`` against each swept key, a panel per key.

    ``runs`` are the runs of one sweep (``chainrun.store.RunData``); ``balls`` are ball
    numbers, 1-based, negative counting from the end (-1: the last ball). Each point
    carries the run's id; a ball a run does not have is left out of it.
    """
    keys = sorted({key for run in runs for key in run.parameters.get("overrides", {})})
    if not keys:
        raise ChainrunError("not a sweep: its runs have no swept keys")
    figure = Figure(figsize=(4.5 * len(keys), 3.4), layout="constrained")
    for panel, key in enumerate(keys, start=1):
        axes = figure.add_subplot(1, len(keys), panel)
        for which, ball in enumerate(balls):
            points = []
            for run in runs:
                value = run.parameters.get("overrides", {}).get(key)
                i = _ball_index(ball, run.n)
                if isinstance(value, (int, float)) and i is not None:
                    points.append((value, run.final_velocity[i]))
            if not points:
                continue
            x, y = np.array(sorted(points)).T
            name = "last ball" if ball == -1 else (f"ball {ball}" if ball > 0
                                                    else f"ball N{ball + 1:+d}")
            axes.plot(x, y, label=name, color="black", gid=f"final_velocity/{key}/{ball}",
                      linestyle=("-", "--", "-.", ":")[which % 4],
                      **MARKERS[which % len(MARKERS)])
        axes.axhline(0.0, color="0.6", linewidth=0.6)
        axes.set_xlabel(key)
        axes.set_ylabel(f"final velocity ({UNITS})")
        axes.legend(fontsize="small")
    experiment = runs[0].parameters.get("experiment", "")
    figure.suptitle(f"{experiment}: {len(runs)} runs", fontsize="medium")
    return figure


def draw_sweep_runs(runs, *, log: bool = False) -> Figure:
    """A panel per run of a sweep: its final velocities against ball number, titled by
    its run id, on a grid of at most 5 columns."""
    cols = min(5, len(runs))
    rows = -(-len(runs) // cols)
    figure = Figure(figsize=(2.6 * cols, 2.2 * rows), layout="constrained")
    for i, run in enumerate(runs):
        axes = figure.add_subplot(rows, cols, i + 1)
        v = run.final_velocity
        axes.plot(np.arange(1, run.n + 1), v, marker="o", markersize=2, color="black",
                  linewidth=0.8, gid=f"final_velocity/{run.parameters.get('run_id', i)}")
        axes.axhline(0.0, color="0.6", linewidth=0.5)
        axes.set_title(str(run.parameters.get("run_id", i)), fontsize="small")
        axes.tick_params(labelsize="x-small")
        if log:
            small = np.abs(v[v != 0.0])
            axes.set_yscale("symlog", linthresh=max(float(small.min()) if small.size
                                                    else 1.0, 1e-12))
    figure.supxlabel("ball", fontsize="small")
    figure.supylabel(f"final velocity ({UNITS})", fontsize="small")
    return figure
