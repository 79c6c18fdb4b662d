"""Numba kernels: plain floats and arrays in SI units, no Python objects, no SciPy/xarray.

``jit`` holds the package's one set of compile options. Kernels compile on first call (not at
import) and are cached on disk (``cache=True``). Numba checks a cached kernel only against its
own source file, not against the kernels it calls in other files: after editing a kernel,
clear the cache (``find src -name '*.nb[ic]' -delete``) or key the cache directory by
`source_digest`, as the test suite does.
"""

import hashlib
from pathlib import Path


def source_digest() -> str:
    """Short hash of every kernel source file (no Numba import: usable before configuring it)."""
    sources = sorted(Path(__file__).parent.glob("*.py"))
    return hashlib.sha256(b"".join(path.read_bytes() for path in sources)).hexdigest()[:16]
