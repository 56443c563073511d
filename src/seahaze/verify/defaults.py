"""The settings ``seahaze verify`` starts from, in a module that imports nothing heavy: the CLI
shows them in its help without loading the calibration scene's geometry (the world, the vessels,
trimesh), which every other ``seahaze`` command would otherwise pay for at start-up.
"""

from __future__ import annotations

TARGET_WIDTH_DEG = 0.2
"""Angular width of every target at the camera (physically thin: see docs/physics.md)."""
DEFAULT_RESOLUTION = (512, 13)
"""Size of the calibration view: 12 targets of 2+ px across 24°, and the horizon rows."""

# Measured on a 2-vCPU machine (docs/physics.md, "Verifying visibility"): 4096 spp give a
# standard error of 0.9 % on V = 1000 m in about two minutes, so 5 % holds the thin targets'
# bias (+1-2 %) plus more than 3 standard errors.
DEFAULT_VISIBILITY_M = 1000.0
"""The level verified when ``--vis`` is not given (m)."""
DEFAULT_SPP = 4096
"""Samples per pixel of each level's calibration render, over all batches."""
DEFAULT_BATCHES = 16
"""Independent batches the samples are split into (their spread gives the standard error)."""
DEFAULT_TOLERANCE = 0.05
"""Largest relative difference between measured and labelled visibility that passes."""
