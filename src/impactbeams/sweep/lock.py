"""Old import path of the output lock: see `impactbeams.lock`.

Kept so that code written against ``impactbeams.sweep.lock`` keeps working.
"""

from impactbeams.lock import OutputInUse, lock_path, output_lock

__all__ = ["OutputInUse", "lock_path", "output_lock"]
