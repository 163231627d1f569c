"""chainrun: exact, event-driven experiments on a line of touching balls struck at one end.

The package owns the whole path from an experiment file to reproducible results:
``config`` (validated experiments), ``solver`` (the event-driven numba solver),
``store`` (the only module that touches HDF5), ``runner`` (runs experiments and sweeps)
and ``cli`` (the ``chainrun`` command).
"""

__version__ = "0.1.0"
