"""``RunSpec``: one fully specified run of an experiment (one point of a sweep), what
the runner hands to a worker: its settings, its resolved configuration and hash, and
its line (``RunSpec.line``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from chainrun.config.line import LineError, is_paper, line_of
from chainrun.config.schema import Chain, Walls, sensor_count
from chainrun.config.sweeps import checked_config, config_hash
from chainrun.errors import ConfigError, one_line
from chainrun.solver import Line


@dataclass(frozen=True)
class RunSpec:
    """One fully specified run of an experiment (one point of a sweep).

    Attributes
    ----------
    experiment : str
        The experiment's ``name``.
    run_id : str
        File-name-safe id, unique within the experiment: ``"run"`` without a sweep,
        else the swept values, e.g. ``"k=2"`` or ``"n=100_k=3"``.
    n, k : int
    alpha : float
    times : ndarray, shape (T,)
        Snapshot times, non-negative and non-decreasing.
    t_end : float or None
    rtol : float
    max_events : int or None
    sensors : tuple of int
        Balls (numbered from 1) whose contact forces are sampled every ``sensor_dt``.
    sensor_dt : float or None
    sensor_end : float or None
        The last time a sample is taken (``output.sensor_end``, by default ``t_end``
        or else the last snapshot time); None without sensors.
    overrides : dict
        The swept keys and their values for this run, e.g. ``{"chain.k": 2}``.
    config : dict
        The resolved configuration of this single run (no ``sweep`` table), as plain
        JSON-compatible data.
    config_hash : str
        sha256 of the canonical JSON of ``config``: two runs with the same hash are
        the same computation.
    source_text : str
        The full text of the experiment file the run came from.
    units : {"paper", "si"}
        The units of the run's line, times and results.
    chain : Chain
        The run's chain (sweep values applied); a spec built in code without one has
        the paper's chain of ``n``, ``k`` and ``alpha``.
    walls : Walls
    check : bool
        Whether to run the line a second time at ``chainrun.check.check_rtol(rtol)``
        and store the spread of each ball's velocities (``solver.check``, or the
        command's ``--check``); not part of ``config`` nor of its hash.

    For a general line, ``k`` is the number of leading balls that move and ``alpha``
    the contacts' exponent, NaN when it varies: what summaries show. The line itself
    is ``line``.
    """

    experiment: str
    run_id: str
    n: int
    k: int
    alpha: float
    times: np.ndarray
    t_end: float | None
    rtol: float
    max_events: int | None
    overrides: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    config_hash: str = ""
    source_text: str = ""
    sensors: tuple[int, ...] = ()
    sensor_dt: float | None = None
    sensor_end: float | None = None
    units: str = "paper"
    chain: Chain | None = None
    walls: Walls | None = None
    check: bool = False

    def for_check(self) -> "RunSpec":
        """The check's run of this one: the same line at ``check_rtol(rtol)``, with
        its own resolved configuration and hash (and no check of its own)."""
        config = checked_config(self.config)
        spec = replace(self, rtol=config["solver"]["rtol"], config=config,
                       config_hash=config_hash(config), check=False)
        line = self.__dict__.get("_line")
        return spec if line is None else spec._keep(line)

    def __post_init__(self):
        if self.chain is None:  # a spec built in code from n, k and alpha alone
            object.__setattr__(self, "chain", Chain(n=self.n, k=self.k, alpha=self.alpha))
        if self.walls is None:
            object.__setattr__(self, "walls", Walls())

    @property
    def is_paper(self) -> bool:
        """Whether the run's line is the paper's, in its units: only n, k and one alpha
        (its observables keep the paper's formulas, its labels say "paper units")."""
        return is_paper(self.chain, self.walls, self.units)

    @property
    def line(self) -> Line:
        """The ``Line`` of this run, in its ``units``: the one built when the file was
        checked, or else (the paper's line, a line longer than ``CHECK_MAX_N``, a spec
        built in code) built on first use and kept.

        Raises
        ------
        ConfigError
            Values that the file's checks could not see (a generated array of a line
            longer than ``CHECK_MAX_N``, a data file changed since it was read).
        """
        line = self.__dict__.get("_line")
        if line is None:
            if self.is_paper:
                line = Line.paper(self.n, self.k, self.alpha)
            else:
                try:
                    line = line_of(self.chain, self.walls, self.units)
                except LineError as exc:
                    raise ConfigError(self.experiment, [
                        one_line(f"run {self.run_id}: {p.line()}") for p in exc.problems]) from None
            self._keep(line)
        return line

    def _keep(self, line: Line) -> "RunSpec":
        object.__setattr__(self, "_line", line)  # a cache, not a field
        return self

    @property
    def sensor_samples(self) -> int:
        """Force samples the run's sensors take: sample times by sensor balls."""
        return sensor_count(self.sensors, self.sensor_dt, self.sensor_end)

    @property
    def damped(self) -> bool:
        """Whether the run's line may dissipate: a contact's or a wall's damping or
        restitution is given (other than a damping of 0 or a restitution of 1). Read
        from the settings, before the line is built: a damped line's state takes more
        memory (``chainrun.limits``)."""
        def given(settings):
            if settings is None:
                return False
            return any(value is not None and not (isinstance(value, (int, float))
                                                  and value == neutral)
                       for value, neutral in ((settings.damping, 0.0),
                                              (settings.restitution, 1.0)))
        walls = self.walls
        return given(self.chain) or given(walls.left) or given(walls.right)
