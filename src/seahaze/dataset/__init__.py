"""The dataset folder: its layout, its manifest and Ultralytics files, and the scene writer.

* :mod:`~seahaze.dataset.layout` — where every file of a dataset folder lives.
* :mod:`~seahaze.dataset.manifest` — ``dataset.json``, ``data.yaml`` and the split lists.
* :mod:`~seahaze.dataset.splits` — scene-disjoint train/val/test splits, stable as a batch grows.
* :mod:`~seahaze.dataset.card` — the dataset card ``README.md``.
* :mod:`~seahaze.dataset.owned` — files a seahaze tool created in a folder it shares with others.
* :mod:`~seahaze.dataset.writer` — a rendered scene's files (imported on its own: it needs the
  render layer's types).

The layout is a contract users and tools rely on: docs/dataset-format.md.
"""

from .layout import Layout
from .manifest import (
    FORMAT_VERSION,
    config_hash,
    data_yaml_text,
    level_entries,
    manifest,
    split_list_text,
)
from .splits import SplitError, SplitFractions

__all__ = [
    "FORMAT_VERSION",
    "Layout",
    "SplitError",
    "SplitFractions",
    "config_hash",
    "data_yaml_text",
    "level_entries",
    "manifest",
    "split_list_text",
]
