"""Parameter sweeps: definitions (TOML), validation, chunked parallel runs that resume.

The data flow, one module each: `definition` (what a sweep is, what it refuses) ->
`plan` (the kernels' inputs, `compute_chunk`; `estimate`: what a run costs) ->
`run` (chunks through a runner; `store` keeps
finished ones for a resume) -> `output` (the map, in memory or streamed
into netCDF). Importing this package loads NumPy only: xarray, netCDF4 and Numba load on use.
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
    default_chunk_cells,
    load_sweep,
    sweep_from_mapping,
)
from impactbeams.sweep.output import map_dataset
from impactbeams.sweep.plan import (
    MAX_SEGMENTS,
    Chunking,
    Plan,
    build_plan,
    code_digest,
    compute_chunk,
)
from impactbeams.sweep.progress import Progress
from impactbeams.sweep.run import (
    Chunk,
    ChunkRunner,
    local_runner,
    run_sweep,
    write_sweep,
)

__all__ = ["CELL_PARAMETERS", "DYNAMICS_OBSERVABLES", "FIRST_IMPACT", "LONG_TIME_OBSERVABLES",
           "LYAPUNOV", "MAX_SEGMENTS", "OBSERVABLES", "Axis", "Chunk", "ChunkRunner", "Chunking",
           "Plan", "Progress", "Sweep", "build_plan", "code_digest", "compute_chunk",
           "default_chunk_cells", "load_sweep", "local_runner", "map_dataset", "run_sweep",
           "sweep_from_mapping", "write_sweep"]
