"""The ``chainrun`` command: thin click commands over library functions of the same names.

One module per command; library errors (``ChainrunError``) become one-line messages and
a non-zero exit status. Nothing here computes or writes anything itself.
"""

from __future__ import annotations

import os

# A chainrun process runs one solver thread, and runs in parallel are processes (make's
# jobs, --jobs workers). numpy's and scipy's OpenBLAS would each start a thread per
# further core when imported, which spin waiting for work that never comes and take CPU
# from the other runs (about 0.15 s of CPU per process on two cores). Set before numpy is
# first imported, which is what reads it; a value the user set stands.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import atexit
import gc

import click

from chainrun import __version__, interrupt
from chainrun.cli.common import Commands
from chainrun.cli.analyze import analyze
from chainrun.cli.animate import animate
from chainrun.cli.info import info
from chainrun.cli.plot import plot
from chainrun.cli.simulate import simulate
from chainrun.cli.spectrum import spectrum


@click.group(cls=Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="chainrun")
def main():
    """Exact, event-driven experiments on a line of balls: struck, driven or at rest.

    Balls of any masses touch (or nearly) in a line, between walls or not; some
    strike the rest, or a wall shakes them. Contacts push with k (compression)^alpha
    and never pull (alpha = 1 linear, 1.5 Hertz: real beads in SI from their
    material and diameter), damped or elastic. chainrun locates every contact
    opening and closing, integrates only the balls that touch, and runs each line to
    its terminal state (or its stop time). The paper's line (N equal balls, the
    first K at velocity 1) is its first example.

    \b
    Examples:
      chainrun simulate configs/examples/damped-cradle.toml   # steel beads in SI
      chainrun simulate configs/table1.toml          # the paper's Table 1
      chainrun simulate my.yaml -o results/mine --jobs 2
      chainrun simulate --help                       # the experiment file format
      chainrun info results/table1                   # what the runs hold, at a glance
      chainrun plot --list                           # the paper's figures and tables
      chainrun analyze fig05 && chainrun plot fig05  # one figure from its runs
      chainrun spectrum configs/examples/granular-crystal.toml   # modes and bands
    """
    # A run leaves a large heap behind (numba, LLVM, scipy, h5py): the interpreter's
    # garbage collections at exit would walk all of it, 0.2-0.3 s of wall time, to free
    # memory the process gives back anyway. Frozen objects are not collected.
    # (Unregistered first: one handler however often the group runs in a process.)
    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    # A terminated run (a job's time limit, `timeout`, a closed terminal's SIGHUP) is an
    # interrupted one: the files being written are discarded, not left half-written
    # beside the finished ones, and the command says how far it got. An interrupt that
    # lands in a callback whose exceptions Python ignores is raised again at the run's
    # next snapshot (chainrun.interrupt).
    interrupt.install()


main.add_command(simulate)
main.add_command(info)
main.add_command(analyze)
main.add_command(plot)
main.add_command(animate)
main.add_command(spectrum)
