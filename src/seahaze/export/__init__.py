"""Views of a finished dataset in the folder layouts other tools read, without copying pixels.

* :mod:`~seahaze.export.source` — the finished dataset an export reads.
* :mod:`~seahaze.export.layouts` — the layouts (``paired``, ``same-name``, ``reside``, ``yolo``,
  ``yolo-hazy``, ``hf``), each planned as an :class:`~seahaze.export.plan.ExportPlan`.
* :mod:`~seahaze.export.hf`, :mod:`~seahaze.export.hf_rows`, :mod:`~seahaze.export.hf_card` —
  the ``hf`` layout: Parquet shards for Hugging Face ``datasets`` and their card.
* :mod:`~seahaze.export.links` — hard links, symbolic links or copies.
* :mod:`~seahaze.export.run` — :func:`export_dataset`.

See docs/dataset-format.md#exports.
"""

from .layouts import LAYOUTS, PAIR_COLUMNS, PAIRS_CSV, reside_ids
from .links import LINK_MODES
from .run import ExportReport, export_dataset
from .source import ExportError

__all__ = [
    "LAYOUTS",
    "LINK_MODES",
    "PAIRS_CSV",
    "PAIR_COLUMNS",
    "ExportError",
    "ExportReport",
    "export_dataset",
    "reside_ids",
]
