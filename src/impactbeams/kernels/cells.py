"""A map cell's run inputs as one `RunInputs` record, and the settings record's lifetime.

The map kernels (`impactbeams.kernels.observables`, `impactbeams.kernels.stroboscope`,
`impactbeams.kernels.lyapunov`) build a cell's inputs with `cell_run` and pass them, whole, to
the kernel that runs the cell, which reads the settings record with `settings_of`. The record
is a view into the inputs' one-element array, which Numba would free after its last use in
the frame that built it (the record does not hold it; a run reading it then read freed
memory): a kernel's caller holds its arguments for the whole call, so reading the record only
from a received `RunInputs` keeps the array alive wherever the record is used.
"""

from impactbeams.kernels.forcing import run_inputs
from impactbeams.kernels.jit import kernel
from impactbeams.kernels.records import RunInputs


@kernel
def cell_run(cell, tables, geometry, switching, t_max, search_span):
    """``RunInputs`` of map cell ``cell`` in its geometry (``forcing.run_inputs``); s.

    ``switching``: the geometry's switching record (`records.SWITCHING`).
    """
    damped, forces, scalars, settings_array, q0, v0, run_switching = run_inputs(
        cell, tables, geometry, switching, t_max, search_span)
    return RunInputs(damped, forces, scalars, settings_array, q0, v0, run_switching)


@kernel
def settings_of(run):
    """The settings record of ``run``, a `RunInputs` the calling kernel received as argument."""
    return run.settings_array[0]
