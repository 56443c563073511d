"""Dataset batches: many scenes, resumable, atomic, locked, parallel (local processes or Dask).

* :mod:`~seahaze.batch.plan` — templates → scenes with their own seeds and variations.
* :mod:`~seahaze.batch.run` — :func:`run_batch`: the locked, resumable run into a folder.
* :mod:`~seahaze.batch.folder` — the folder's manifest, what changed, clean-up.
* :mod:`~seahaze.batch.lock` — one seahaze process per folder.
* :mod:`~seahaze.batch.executors` — this process, local worker processes, or Dask.
* :mod:`~seahaze.batch.progress` — the progress bar and the JSON-lines log.

See docs/batches.md.
"""

from ..seeds import scene_seed
from .errors import BatchRefusedError, ConfigChangedError, DatasetError, DatasetLockedError
from .lock import LOCK_NAME, DatasetLock
from .plan import BatchPlan, SceneJob, plan_scenes, vary_scene
from .progress import Reporter
from .report import BatchReport
from .run import BatchOptions, run_batch

__all__ = [
    "LOCK_NAME",
    "BatchOptions",
    "BatchPlan",
    "BatchRefusedError",
    "BatchReport",
    "ConfigChangedError",
    "DatasetError",
    "DatasetLock",
    "DatasetLockedError",
    "Reporter",
    "SceneJob",
    "plan_scenes",
    "run_batch",
    "scene_seed",
    "vary_scene",
]
