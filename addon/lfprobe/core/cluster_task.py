"""The function a Dask worker runs for a cluster bake (core/cluster_bake.py).

It is shipped to the workers by value (cloudpickle), not by its module's name, and imports
only the standard library: inside Blender 4.2+ the add-on's package is
``bl_ext.<repository>.lfprobe``, which a worker cannot import. The worker imports ``lfprobe``
from its own path (PYTHONPATH=<lfprobe>/addon), and every argument and result is a plain
Python value for the same reason."""

import importlib

WORKER_MODULE = "lfprobe.core.cluster_bake"


def run_bake_task(spec: dict, positions: list, indices: list, staging: str) -> dict:
    try:
        module = importlib.import_module(WORKER_MODULE)
    except ImportError as error:
        raise ImportError(f"this Dask worker cannot import lfprobe ({error}); start it with "
                          "PYTHONPATH=<lfprobe>/addon dask worker ADDRESS --nthreads 1") from None
    return module.bake_probe_batch(spec, positions, indices, staging)
