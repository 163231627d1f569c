"""A first session with chainrun from Python: a run, a sweep, a plot.

Run it as ``python docs/tutorial.py [FOLDER]``; it writes into FOLDER (default:
``tutorial-output``) and prints what it finds. The test suite runs it
(``tests/integration/test_tutorial.py``), so every line here works as written.
"""

import sys
from pathlib import Path

import chainrun

out = Path(sys.argv[1] if len(sys.argv) > 1 else "tutorial-output")
out.mkdir(parents=True, exist_ok=True)

# --- 1. One run --------------------------------------------------------------------------
# Newton's cradle of the paper's Table 1: five balls with Hertz contacts (alpha = 1.5),
# the first striking the others at velocity 1 (the paper's units: masses, stiffness and
# striker speed 1). The keyword tables are those of an experiment file.
cradle = chainrun.simulate(
    name="cradle",
    chain={"n": 5, "k": 1, "alpha": 1.5},
    output={"times": {"start": 0, "stop": 10, "step": 0.1}},
)
# An xarray Dataset: dimensions time (the snapshots), ball (1..5) and event (the log of
# contacts opening and closing).
print(cradle.final_velocity.round(4).values)       # Table 1, K = 1
assert abs(cradle.final_velocity.sel(ball=5).item() - 0.9888) < 5e-5
print(f"terminal state at t = {cradle.attrs['end_time']:.4f}, "
      f"{cradle.sizes['event']} contact events")

# Energy is conserved along the way: kinetic plus what the contacts store.
total = cradle.kinetic_energy + cradle.potential_energy
print(f"energy drift {float(abs(total - 0.5).max()):.1e}")

# --- 2. A sweep --------------------------------------------------------------------------
# The whole of Table 1: the number of striking balls K from 1 to 4. A sweep gives a
# DataTree, one Dataset per run, named by the swept value.
table1 = chainrun.simulate(
    name="table1",
    chain={"n": 5, "alpha": 1.5},
    sweep={"chain.k": [1, 2, 3, 4]},
)
for run_id, node in table1.children.items():
    v = node.to_dataset().final_velocity.values
    print(run_id, " ".join(f"{x:8.4f}" for x in v))

# --- 3. A file, and a plot -----------------------------------------------------------
# A longer line in an experiment file, run by the same pipeline as `chainrun simulate`
# (whose run file chainrun.open_run reads back), then drawn.
config = out / "wave.toml"
config.write_text("""name = "wave"
[chain]
n = 40
k = 2
alpha = 1.5
[output]
times = {start = 0, stop = 50, step = 0.25}
""")
wave = chainrun.simulate(config)
fastest = wave.final_velocity.idxmax("ball").item()
print(f"wave: ball {fastest} leaves fastest, at {wave.final_velocity.max().item():.4f}")

# The command line writes the run file and draws its standard views (the same as
# `chainrun simulate wave.toml -o OUT/wave` then `chainrun plot OUT/wave/run.h5`).
from click.testing import CliRunner  # noqa: E402  (the command, called from Python)

from chainrun.cli import main  # noqa: E402

CliRunner().invoke(main, ["simulate", str(config), "-o", str(out / "wave")],
                   catch_exceptions=False)
from chainrun.plotting import render_run  # noqa: E402

figures = render_run(out / "wave" / "run.h5", ["spacetime", "final"], out=out / "figures")
print("figures:", ", ".join(p.name for p in figures))
assert chainrun.open_run(out / "wave" / "run.h5").final_velocity.equals(wave.final_velocity)
