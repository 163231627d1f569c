"""An ensemble: the runs of one line over random draws, as statistics over the runs.

Read from run files only (``chainrun.store.RunData``). An output folder holds an
ensemble when its runs differ only in their random draws: every swept key is a
generator's seed (``chain.mass.seed``) or the replica number (``replicas``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from chainrun.errors import ChainrunError

__all__ = ["Ensemble", "ensemble", "is_ensemble"]


def is_ensemble(runs) -> bool:
    """Whether the runs are one line over random draws: more than one, and every swept
    key a generator's seed or the replica number."""
    keys = {key for run in runs for key in run.parameters.get("overrides", {})}
    return len(runs) > 1 and bool(keys) and all(
        key == "replica" or key.endswith(".seed") for key in keys)


@dataclass(frozen=True)
class Ensemble:
    """Statistics of an ensemble's runs, in their units.

    ``final`` holds the mean, standard deviation (over runs, ddof = 1), smallest and
    largest final velocity of each ball, shape (N,) each. ``energy_left`` is, for each
    run at each snapshot time ``times``, the share of its impact energy still in the
    line (kinetic and contact energy; the rest was dissipated), shape (R, T); None
    when no run dissipated (all of it stays), or the runs' snapshot times differ or
    are fewer than two. ``terminal`` says for each run whether it reached its terminal
    state (else its "final" velocities are those where it stopped), ``end_times`` when
    it ended, shape (R,) each.
    """

    runs: int
    units: str
    final: dict[str, np.ndarray]
    times: np.ndarray | None
    energy_left: np.ndarray | None
    terminal: np.ndarray
    end_times: np.ndarray


def ensemble(runs) -> Ensemble:
    """The statistics of ``runs`` (``RunData`` of one line over random draws).

    Raises
    ------
    ChainrunError
        If the runs' lines differ in length, or there are fewer than two.
    """
    if len(runs) < 2 or len({run.n for run in runs}) != 1:
        raise ChainrunError("an ensemble needs two runs or more, of lines of one length")
    finals = np.array([np.asarray(run.final_velocity) for run in runs])
    final = {"mean": finals.mean(axis=0), "sd": finals.std(axis=0, ddof=1),
             "min": finals.min(axis=0), "max": finals.max(axis=0)}
    ended = {"terminal": np.array([bool(run.terminal) for run in runs]),
             "end_times": np.array([float(run.end_time) for run in runs])}
    times = runs[0].times
    if (times.size < 2 or not all(np.array_equal(run.times, times) for run in runs)
            or not any(run.dissipated_energy > 0.0 for run in runs)):
        return Ensemble(len(runs), runs[0].units, final, None, None, **ended)
    left = np.array([(run.observables["kinetic_energy"] + run.observables["potential_energy"]
                      - run.baseline_energy) / run.impact_energy for run in runs])
    return Ensemble(len(runs), runs[0].units, final, times, left, **ended)
