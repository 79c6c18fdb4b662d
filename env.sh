. /work/venv/bin/activate
export PYTHONPATH=/work/wt/cont31/src
export NUMBA_CACHE_DIR=/work/wt/cont31/.numba-cache
