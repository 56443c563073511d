"""Bounding boxes from the instance pass, and the YOLO text format.

Boxes are tight around the pixels whose centre ray first hits a vessel, so they are
occlusion-aware by construction: a vessel behind another gets the box of its visible part.
Box edges lie on pixel boundaries: a vessel covering pixel columns ``i0..i1`` spans
``[i0, i1 + 1)`` in pixel coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Box:
    """An axis-aligned box in pixel coordinates (edges), for one vessel."""

    vessel: int
    class_id: int
    x0: float
    y0: float
    x1: float
    y1: float
    pixels: int
    """Number of visible pixels of the vessel."""
    visible_fraction: float = 1.0
    """Visible pixels over the pixels the vessel would cover with nothing in front of it."""

    def yolo(self, width: int, height: int) -> tuple[float, float, float, float]:
        """Normalised ``(cx, cy, w, h)`` for YOLO."""
        return (
            (self.x0 + self.x1) / 2 / width,
            (self.y0 + self.y1) / 2 / height,
            (self.x1 - self.x0) / width,
            (self.y1 - self.y0) / height,
        )


def boxes_from_instances(
    instance: np.ndarray,
    class_ids: list[int],
    footprint_px: np.ndarray | None = None,
    min_box_px: float = 1.0,
    min_visible_fraction: float = 0.0,
) -> list[Box]:
    """Tight boxes of the vessels visible in an (H, W) instance map (-1 = no vessel).

    A vessel is labelled when its box is at least ``min_box_px`` wide and high and at least
    ``min_visible_fraction`` of its unoccluded footprint (``footprint_px``, pixels whose ray
    meets it behind anything) is visible.
    """
    boxes = []
    for vessel, class_id in enumerate(class_ids):
        rows, cols = np.nonzero(instance == vessel)
        if len(rows) == 0:
            continue
        total = int(footprint_px[vessel]) if footprint_px is not None else len(rows)
        fraction = len(rows) / max(total, len(rows))
        box = Box(
            vessel,
            class_id,
            float(cols.min()),
            float(rows.min()),
            float(cols.max() + 1),
            float(rows.max() + 1),
            len(rows),
            fraction,
        )
        if min(box.x1 - box.x0, box.y1 - box.y0) < min_box_px or fraction < min_visible_fraction:
            continue
        boxes.append(box)
    return boxes


def yolo_text(boxes: list[Box], width: int, height: int) -> str:
    """YOLO label file content: one ``class cx cy w h`` line per box, 6 decimals."""
    lines = []
    for box in boxes:
        cx, cy, w, h = box.yolo(width, height)
        lines.append(f"{box.class_id} {cx:.6f} {cy:.6f} {w:.6f} {h:.6f}")
    return "".join(line + "\n" for line in lines)
