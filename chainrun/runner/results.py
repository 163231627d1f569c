"""What a sweep reports: typed results and progress, which the command line puts into
words (``chainrun.cli.text``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from chainrun.check import Check


@dataclass(frozen=True)
class RunSummary:
    """What a person (and the index file) needs to know about one run with a file.

    ``skipped`` is True for a run whose file was already there (from an earlier,
    identical computation) and was read instead of computed.
    """

    run_id: str
    file: str
    n: int
    k: int
    alpha: float
    outcome: str
    ok: bool
    terminal: bool
    end_time: float
    events: int
    steps: int
    momentum_error: float
    energy_error: float
    wall_time: float
    config_hash: str
    message: str
    final_velocity: np.ndarray
    skipped: bool = False
    dissipated: float = 0.0  # share of the energy taken up that the damping took
    units: str = "paper"  # the run's units: "paper" or "si"
    check: Check | None = None  # the conditioning check, if the run had one
    speed: float = 1.0  # what the check's spreads are measured against (reference_speed)
    speed_name: str = "the impact speed"
    driven: bool = False  # the line is driven: it took up its impact and the drives' work
    energy_floor: float = 0.0  # the energy_error rounding alone can leave (Diagnostics)
    momentum_scale: float = 1.0  # M V of the line's scales, the unit of momentum_error

    def index_entry(self) -> dict:
        return dict(
            run_id=self.run_id, file=self.file, n=self.n, k=self.k, alpha=self.alpha,
            outcome=self.outcome, terminal=self.terminal, end_time=self.end_time,
            events=self.events, wall_time=self.wall_time, config_hash=self.config_hash,
        )


@dataclass(frozen=True)
class RunError:
    """A run that raised (or whose worker was lost for good): it has no file."""

    run_id: str
    message: str
    ok = False
    skipped = False


@dataclass(frozen=True)
class SweepProgress:
    """Counts of a sweep's runs, for a progress display.

    ``running`` counts runs handed to the executor and not finished, up to the
    number of runs it can compute at once; the rest of the unfinished runs wait.
    """

    total: int
    done: int = 0
    running: int = 0
    failed: int = 0
    skipped: int = 0
    current: str = ""  # e.g. "k=2 t = 12.5", for a run computed in this process

    @property
    def finished(self) -> int:
        return self.done + self.failed + self.skipped


@dataclass
class SweepResult:
    """What a sweep did.

    Attributes
    ----------
    runs : list of RunSummary or RunError
        Every run, in the experiment's run order.
    index : Path
        The index file written (it lists the runs that have a file).
    workers : str
        Where the runs were computed, e.g. "in this process" or "on the Dask
        scheduler at tcp://10.0.0.5:8786"; empty if nothing was computed.
    """

    runs: list[RunSummary | RunError]
    index: Path
    workers: str = ""

    @property
    def summaries(self) -> list[RunSummary]:
        """Runs with a file, computed now or skipped, in run order."""
        return [r for r in self.runs if isinstance(r, RunSummary)]

    @property
    def failures(self) -> list[RunSummary | RunError]:
        """Runs that raised or ended in a non-ok outcome (skipped ones included)."""
        return [r for r in self.runs if not r.ok]

    @property
    def computed(self) -> list[RunSummary | RunError]:
        """Runs tried now (failed ones included)."""
        return [r for r in self.runs if not r.skipped]

    @property
    def skipped(self) -> list[RunSummary]:
        """Runs read back from a file that matched (failed ones included)."""
        return [r for r in self.summaries if r.skipped]
