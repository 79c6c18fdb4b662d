"""Parameter sweeps: definitions (TOML), validation, chunked parallel runs that resume.

The data flow, one module each: :mod:`~impactbeams.sweep.definition` (what a sweep is) ->
:mod:`~impactbeams.sweep.plan` (the kernels' inputs, :func:`compute_chunk`) ->
:mod:`~impactbeams.sweep.run` (chunks through a runner; :mod:`~impactbeams.sweep.store` keeps
finished ones for a resume) -> :mod:`~impactbeams.sweep.output` (the map Dataset).
"""

from impactbeams.sweep.definition import (
    CELL_PARAMETERS,
    DYNAMICS_OBSERVABLES,
    FIRST_IMPACT,
    LONG_TIME_OBSERVABLES,
    LYAPUNOV,
    OBSERVABLES,
    Axis,
    Sweep,
    load_sweep,
    sweep_from_mapping,
)
from impactbeams.sweep.output import map_dataset
from impactbeams.sweep.plan import MAX_SEGMENTS, Plan, build_plan, compute_chunk
from impactbeams.sweep.progress import Progress
from impactbeams.sweep.run import (
    Chunk,
    ChunkRunner,
    chunk_bounds,
    default_chunk_cells,
    local_runner,
    run_sweep,
)

__all__ = ["CELL_PARAMETERS", "DYNAMICS_OBSERVABLES", "FIRST_IMPACT", "LONG_TIME_OBSERVABLES",
           "LYAPUNOV", "MAX_SEGMENTS", "OBSERVABLES", "Axis", "Chunk", "ChunkRunner", "Plan",
           "Progress", "Sweep", "build_plan", "chunk_bounds", "compute_chunk",
           "default_chunk_cells", "load_sweep", "local_runner", "map_dataset", "run_sweep",
           "sweep_from_mapping"]
