"""What several test files share: running the real ``chainrun simulate`` on a config,
the paper's Table 1 as printed, building the paper's cheap artefacts, the known solver
defects, the driven chain of the transmission tests, and the damped laws whose kernels
have loops of their own."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from chainrun.cli import main
from chainrun.solver import _state

#: The repository (tests/ is one level below it).
ROOT = Path(__file__).resolve().parents[1]

#: Table 1 of the paper as printed: final velocities of the N = 5 Hertz line, by K.
TABLE1 = {
    1: ["-0.0711", "-0.0303", "-0.0145", "0.1270", "0.9888"],
    2: ["-0.1126", "-0.0420", "0.2145", "0.8004", "1.140"],
    3: ["-0.1397", "0.1996", "0.7855", "1.042", "1.113"],
    4: ["0.0112", "0.8729", "1.015", "1.030", "1.071"],
}

#: The damped window passes' cases, (mode, alpha, beta): each named law has a loop of its
#: own, the others share the general one (beta None: an exponent per lane).
DAMPED_LOOPS = [
    (_state.MODE_HERTZ, 1.5, 0.25),    # Tsuji on Hertz: a loop of its own
    (_state.MODE_HERTZ, 1.5, 0.5),     # Kuwabara-Kono on Hertz: a loop of its own
    (_state.MODE_LINEAR, 1.0, 0.0),    # a dashpot on linear: a loop of its own
    (_state.MODE_POWER, 2.0, 0.5),     # another law: the general loop
    (_state.MODE_HERTZ, 1.5, None),    # exponents that differ: the general loop
]
#: Rows of a window's lane parameters (WP).
WINDOW_ROWS = max(getattr(_state, name) for name in dir(_state) if name.startswith("W_")) + 1

#: The paper's artefacts cheap enough to build in the test suite (no dense snapshots).
FAST = ("fig01", "fig02", "fig03", "fig04", "fig05", "fig06", "fig07", "sec4", "fig08",
        "fig09", "fig12", "fig13", "table1")


def simulate_text(folder: Path, text: str, name: str = "experiment") -> Path:
    """Write the experiment ``text`` into ``folder`` as ``<name>.toml``, run ``chainrun
    simulate`` on it into ``folder/out`` and return that output folder."""
    config = folder / f"{name}.toml"
    config.write_text(text)
    out = folder / "out"
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


def build(name: str, results: Path):
    """Simulate the experiments of artefact ``name`` (and of those it needs) into
    ``results`` and analyze it; return its ``AnalysisData``."""
    from chainrun import artefacts
    from chainrun.analysis import analyze
    from chainrun.config import load_experiment
    from chainrun.runner import simulate_experiment
    from chainrun.store import read_analysis

    artefact = artefacts.get(name)
    for need in artefact.needs:
        if not artefacts.analysis_path(need, results).exists():
            build(need, results)
    for experiment in artefact.experiments:
        index = artefacts.index_path(experiment, results)
        if not index.exists():
            spec = load_experiment(ROOT / "configs" / f"{experiment}.toml")
            simulate_experiment(spec, index.parent, jobs=1)
    return read_analysis(analyze(name, results=results))


def driven_sweep(name: str, n: int, frequencies, *, mass=None, sensor_dt: float = 0.05,
                 ramp: float = 30.0, t_end: float = 120.0, description: str | None = None) -> str:
    """The transmission tests' experiment file: a Hertz line of ``n`` beads in paper
    units (masses ``mass`` in turn, else 1) between two walls under a load of 1, its left
    wall shaken by 1e-6 at each of ``frequencies`` (a sweep), starting over ``ramp``,
    run to ``t_end``, with force sensors in its first and last beads."""
    lines = [f'name = "{name}"']
    if description is not None:
        lines.append(f'description = "{description}"')
    lines += ["[chain]", f"n = {n}", "k = 0", "alpha = 1.5"]
    if mass is not None:
        lines.append("mass = {pattern = [" + ", ".join(repr(float(m)) for m in mass) + "]}")
    lines += ["precompression = 1.0", "[walls.left]",
              f"motion = {{amplitude = 1.0e-6, frequency = {float(frequencies[0])!r}, "
              f"ramp = {float(ramp)!r}}}",
              "[walls.right]", "[output]", f"sensors = [1, {n}]",
              f"sensor_dt = {float(sensor_dt)!r}", "[solver]", f"t_end = {float(t_end)!r}",
              "[sweep]",
              '"walls.left.motion.frequency" = ['
              + ", ".join(repr(float(f)) for f in frequencies) + "]"]
    return "\n".join(lines) + "\n"
