"""A first session with chainrun from Python: a run, a sweep, a plot, real beads in SI
with force sensors, and an ensemble over random seeds.

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
# An xarray Dataset: dimensions time (the snapshots), ball (1..5), contact (1..4, the
# pairs of neighbours), wall (left, right) and event (the log of contacts opening and
# closing).
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
fastest = int(wave.final_velocity.idxmax("ball"))
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

# --- 4. Real beads, in SI units, with force sensors -----------------------------------
# Thirty stainless-steel beads of 8 mm touch in a line against a steel wall; one more
# strikes them at 0.3 m/s. Every contact loses energy: a coefficient of restitution of
# 0.9 under Tsuji's law, the same at every impact speed. Balls 10 and 20 carry force
# sensors, sampled every 0.1 us. Everything is in SI: s, m, m/s, kg, N, J.
beads = chainrun.simulate(
    name="beads",
    units="si",
    chain={"n": 30, "k": 1, "speed": 0.3, "diameter": 0.008,
           "material": "stainless_steel", "restitution": 0.9, "damping_law": "tsuji"},
    walls={"right": {"material": "steel"}},
    output={"times": {"start": 0.0, "stop": 4.0e-4, "step": 5.0e-6},
            "sensors": [10, 20], "sensor_dt": 1.0e-7},
    solver={"t_end": 4.0e-4},
)
# The line is in the Dataset, per ball and per contact, with its units.
print(f"beads: {beads.mass.values[0] * 1e3:.5f} g each (stored in {beads.mass.attrs['units']}), "
      f"contact stiffness {beads.stiffness.values[0]:.4g} {beads.stiffness.attrs['units']}")
# What the sensors recorded, measured: at each, the first pulse's peak contact force,
# its time, width and arrival, and the wave's speed fitted through the peak times
# (chainrun.pulses; docs/guide.md, "Pulse measurements", defines each number).
pulses = chainrun.pulses(beads)
for ball in pulses.sensor.values:
    p = pulses.sel(sensor=ball)
    print(f"beads: sensor in ball {ball}: peak force {p.peak_force.item():.3f} N at "
          f"{p.peak_time.item() * 1e6:.2f} us, width {p.width.item() * 1e6:.2f} us")
print(f"beads: the wave runs at {pulses.wave_speed_si.item():.1f} m/s")
# The energy balance: kinetic + contacts + dissipated stays at the impact energy.
initial = 0.5 * float((beads.mass * beads.initial_velocity**2).sum())
total = beads.kinetic_energy + beads.potential_energy + beads.dissipated_energy
print(f"beads: energy balance to {float(abs(total - initial).max()) / initial:.1e}, "
      f"{beads.dissipated_energy[-1].item() / initial:.0%} dissipated by t = 400 us")

# --- 5. An ensemble over random seeds --------------------------------------------------
# A disordered line: masses drawn uniformly between 1 and 3, a seed per run. Eight
# replicas move the seed on by 0..7; `chainrun.open_sweep` reads the eight runs as one
# Dataset along a dimension "run", and `chainrun plot` draws their mean and spread.
ensemble = out / "disorder.toml"
ensemble.write_text("""name = "disorder"
[chain]
n = 40
k = 1
alpha = 1.5
mass = {random = "uniform", low = 1.0, high = 3.0, seed = 1}
[output]
times = {start = 0, stop = 100, step = 2}
[sweep]
replicas = 8
""")
CliRunner().invoke(main, ["simulate", str(ensemble), "-o", str(out / "disorder")],
                   catch_exceptions=False)
runs = chainrun.open_sweep(out / "disorder")
mean = runs.final_velocity.mean("run")
spread = runs.final_velocity.std("run", ddof=1)  # the sample standard deviation
print(f"ensemble: {runs.sizes['run']} runs; ball 1 rebounds at {mean.sel(ball=1).item():.3f} "
      f"+- {spread.sel(ball=1).item():.3f}, the last leaves at {mean.isel(ball=-1).item():.3f} "
      f"+- {spread.isel(ball=-1).item():.3f}")
CliRunner().invoke(main, ["plot", str(out / "disorder"), "--what", "final",
                          "-o", str(out / "disorder-figures")], catch_exceptions=False)
print("ensemble figures:", ", ".join(sorted(p.name for p in (out / "disorder-figures").glob("*.png")
                                            if not p.name.startswith("replica"))))
