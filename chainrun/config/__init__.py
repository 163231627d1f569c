"""Experiment files: the one schema for YAML and TOML, validation, and sweep expansion.

This package owns turning config text into frozen, validated objects: ``text`` reads
TOML and YAML within limits, ``schema`` holds the tables' models, ``drives`` a wall's
motion and a ball's force in time, ``problems`` the one-line messages naming a key,
``sweeps`` the combinations of a sweep, their run ids and hashes, ``line`` the checks
of a run's line (built by ``chainrun.solver.build``), ``experiment`` the whole file
and ``run`` the ``RunSpec`` of each combination. Nothing else in chainrun parses
experiment files, and the package reads nothing but the file it is given and the data
files it names (``chainrun.generators``).

The schema (TOML shown; YAML has the same structure)::

    name = "table1"                  # the output folder: 1-100 of [A-Za-z0-9._-], no leading
                                     # or trailing ".", not a reserved device name (CON, NUL...)
    description = "..."              # optional
    [chain]
    n = 5                            # balls, 1 <= n < 2**63 (memory is checked when run)
    k = 1                            # impacting balls at velocity 1, 0 <= k <= n
    alpha = 1.5                      # contact exponent, >= 1 (1 linear, 1.5 Hertz)
    # any line (docs/guide.md): per ball mass, velocity (instead of k), force, and in SI
    # diameter, material (or young, poisson, density); per contact stiffness, alpha
    # (<= MAX_ALPHA), gap: a number, a list or a generator table (chainrun.generators);
    # speed (with k), precompression; top-level units = "paper" | "si"; dissipation:
    # per contact damping (>= 0) and damping_exponent (>= 0), or restitution (0 < e <= 1)
    # with damping_law ("dashpot" | "kuwabara-kono" | "tsuji") and, where e depends on
    # the impact speed, restitution_speed (> 0)
    # drive = [{ball = 1, amplitude = 0.1, frequency = 0.2, ramp = 5.0}]: forces in time
    [walls.right]                    # optional, likewise [walls.left]
    stiffness = 1.0                  # alpha, gap; or material (SI); the dissipation keys
    # motion = {amplitude = 1e-3, frequency = 0.2, ramp = 5.0}: the wall moves; or a
    # list of such tables (their sum), or {file = "drive.csv"} (times, displacements)
    [output]                         # optional
    times = [0.0, 5.0]               # or {start = 0, stop = 60, step = 5}, stop inclusive;
                                     # none after solver.t_end
    [solver]                         # optional
    t_end = 100.0                    # default: run to the terminal state
    rtol = 1e-12                     # in [1e-15, 1e-3]
    max_events = 1000000             # default: no limit
    check = false                    # true: run again at a tenth of rtol, store the spreads
    [sweep]                          # optional: the cartesian product of the lists
    "chain.k" = [1, 2, 3, 4]         # at most MAX_RUNS runs, MAX_SNAPSHOTS snapshots in all

Every problem in a file is reported at once, one line each naming the dotted key, as a
``chainrun.errors.ConfigError``; ``load_experiment`` and ``parse_experiment`` raise
nothing else, whatever the text (``tests/property/test_fuzz.py`` checks it).
"""

from chainrun.config.drives import DriveSpec
from chainrun.config.experiment import Experiment
from chainrun.config.line import LineError, line_of
from chainrun.config.run import RunSpec
from chainrun.config.schema import (MAX_ALPHA, UNITS, Chain, Output, SolverSettings,
                                    WallSettings, Walls)
from chainrun.config.sweeps import (MAX_RUN_ID, MAX_RUNS, MAX_SNAPSHOTS, SWEEPABLE_KEYS,
                                    checked_config, config_hash)
from chainrun.config.text import MAX_TEXT, MAX_VALUES, load_experiment, parse_experiment

__all__ = [
    "Chain",
    "DriveSpec",
    "Experiment",
    "LineError",
    "MAX_ALPHA",
    "MAX_RUNS",
    "MAX_RUN_ID",
    "MAX_SNAPSHOTS",
    "MAX_TEXT",
    "MAX_VALUES",
    "Output",
    "RunSpec",
    "SWEEPABLE_KEYS",
    "SolverSettings",
    "UNITS",
    "WallSettings",
    "Walls",
    "checked_config",
    "config_hash",
    "line_of",
    "load_experiment",
    "parse_experiment",
]
