"""Parameter sweeps: a study over a grid of parameters, on Dask, into one xarray dataset.

``supercoil sweep STUDY.toml`` (:mod:`supercoil.cli.sweep`) in Python::

    from supercoil.sweeps import load_sweep, load_sweep_study, run_sweep

    sweep = load_sweep_study("examples/sweep_hat_curves.toml")  # the grid, validated
    run_sweep(sweep, "hat_curves", workers=2)                    # DIR/tasks/, DIR/sweep.nc
    dataset = load_sweep("hat_curves")                           # an xarray.Dataset

:mod:`~supercoil.sweeps.grid` reads the ``[sweep]`` table, :mod:`~supercoil.sweeps.driver`
runs the tasks, :mod:`~supercoil.sweeps.summary` keeps the numbers of each result and
:mod:`~supercoil.sweeps.dataset` gathers them. Dask, xarray and h5netcdf (the ``sweep``
extra) are imported only when a sweep runs or a dataset is built or read.
"""

from supercoil.sweeps.dataset import load_sweep
from supercoil.sweeps.driver import SweepOutcome, run_sweep
from supercoil.sweeps.grid import SweepStudy, load_sweep_study, parse_sweep_study

__all__ = ["SweepOutcome", "SweepStudy", "load_sweep", "load_sweep_study", "parse_sweep_study",
           "run_sweep"]
