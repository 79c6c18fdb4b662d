"""Numba kernels: plain floats and arrays in SI units, no Python objects, no SciPy/xarray.

``jit`` holds the package's one set of compile options. Kernels compile on first call (not at
import) and are cached on disk (``cache=True``).
"""
