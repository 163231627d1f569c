"""chainrun: exact, event-driven experiments on a line of touching balls struck at one end.

The package owns the whole path from an experiment file to reproducible results:
``config`` (validated experiments), ``solver`` (the event-driven numba solver),
``store`` (the only module that touches HDF5), ``runner`` (runs experiments and sweeps)
and ``cli`` (the ``chainrun`` command); ``api`` is the same from Python::

    import chainrun
    ds = chainrun.simulate("cradle.toml")      # an xarray Dataset
    ds = chainrun.open_run("results/cradle/run.h5")
    ds = chainrun.open_sweep("results/disorder")  # every run, along a dimension "run"
    p = chainrun.pulses("results/solitary/run.h5")  # force sensors: pulses, wave speed
    ds = chainrun.spectrum("crystal.toml")     # the line's linear spectrum at rest
    t = chainrun.transmission("results/driven-dimer")  # a driven sweep's transmission
"""

__version__ = "0.1.0"

__all__ = ["open_run", "open_sweep", "pulses", "simulate", "spectrum", "transmission"]


def __getattr__(name):
    # imported on first use: ``import chainrun`` stays light for the command line
    if name in __all__:
        from chainrun import api

        return getattr(api, name)
    raise AttributeError(f"module 'chainrun' has no attribute {name!r}")
