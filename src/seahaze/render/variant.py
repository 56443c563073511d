"""Choose the Mitsuba variant and find a libLLVM that drjit can use.

Mitsuba's ``llvm_*`` variants JIT-compile kernels with libLLVM. Debian 12's default LLVM 15 makes
drjit abort ("Cannot select ... fminimum"); LLVM 19 (``apt-get install libllvm19``) works. drjit
reads ``DRJIT_LIBLLVM_PATH`` when its LLVM backend starts, so the path is set before Mitsuba is
imported. ``auto`` tries ``cuda_ad_rgb`` (where a GPU works), then ``llvm_ad_rgb``.

Only these two variants are offered (:data:`SUPPORTED_VARIANTS`): seahaze's passes trace whole
images as vectorised JIT arrays (the geometry pass, the ``physical`` integrator) and read RGB
radiance, so the ``scalar_*`` variants (no vectorised shape pointers: ``mi.ShapePtr`` does not
exist there) and the ``*_mono`` and ``*_spectral*`` variants fail every scene. Without a GPU and
without libLLVM there is no fallback: the error says how to install libLLVM.
"""

from __future__ import annotations

import glob
import os
import re
from pathlib import Path

from ..spec import MITSUBA_VARIANTS

MIN_LLVM_MAJOR = 16
"""Oldest libLLVM accepted; 15 aborts inside drjit, 19 is the version tested here."""

_LLVM_DIRS = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib64",
    "/usr/lib",
    "/usr/local/lib",
)
SUPPORTED_VARIANTS = MITSUBA_VARIANTS
"""The Mitsuba variants seahaze renders with, in the order ``auto`` tries them."""
_INSTALL_LLVM = "install libLLVM >= 16 with 'apt-get install libllvm19' (scripts/bootstrap.sh)"
_selected: str | None = None


def _llvm_major(path: str) -> int | None:
    match = re.search(r"libLLVM[-.]?(?:so\.)?(\d+)", Path(path).name)
    return int(match[1]) if match else None


def find_libllvm() -> str | None:
    """Path of the newest libLLVM with major version >= MIN_LLVM_MAJOR, or None."""
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env and Path(env).exists():
        return env
    candidates = []
    for folder in _LLVM_DIRS:
        for path in glob.glob(os.path.join(folder, "libLLVM*.so*")):
            major = _llvm_major(path)
            if major is not None and major >= MIN_LLVM_MAJOR:
                candidates.append((major, path))
    return max(candidates)[1] if candidates else None


class VariantError(RuntimeError):
    """The requested Mitsuba variant cannot run on this machine."""


_CUDA_DIRS = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib64",
    "/usr/local/nvidia/lib64",
    "/usr/lib/wsl/lib",
)
"""Where NVIDIA's driver library ``libcuda`` usually lies when the dynamic loader's own search
(``ld.so.cache``, ``LD_LIBRARY_PATH``) does not know it (GPU containers mount it under
``/usr/local/nvidia``)."""


def _libcuda_loadable() -> bool:
    """Whether the driver library loads: as the dynamic loader finds it, else from
    :data:`_CUDA_DIRS`."""
    import ctypes

    candidates = ["libcuda.so.1", "libcuda.so"]
    for folder in _CUDA_DIRS:
        candidates += sorted(glob.glob(os.path.join(folder, "libcuda.so*")))
    for name in candidates:
        try:
            ctypes.CDLL(name)
        except OSError:
            continue
        return True
    return False


def _cuda_usable() -> bool:
    """True where an NVIDIA driver is present (a device node and a loadable ``libcuda``);
    checked before touching the CUDA backend."""
    devices = any(Path(p).exists() for p in ("/dev/nvidia0", "/dev/nvidiactl"))
    return devices and _libcuda_loadable()


def _try_set(name: str) -> bool:
    import mitsuba as mi

    if name not in mi.variants():
        return False
    try:
        mi.set_variant(name)
    except Exception:
        return False
    return True


def select_variant(requested: str = "auto") -> str:
    """Activate and return a Mitsuba variant (``auto`` or an explicit name such as ``llvm_ad_rgb``).

    Raises :class:`VariantError` with the available variants for a name that cannot run.
    """
    global _selected
    if _selected is not None and requested in ("auto", _selected):
        return _selected
    llvm = find_libllvm()
    if llvm:
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
    import mitsuba as mi

    if requested != "auto":
        if requested not in SUPPORTED_VARIANTS:
            raise VariantError(
                f"variant {requested!r} is not supported; choose one of: auto, "
                f"{', '.join(SUPPORTED_VARIANTS)} (seahaze traces images as vectorised JIT "
                "arrays in RGB: scalar_*, *_mono and *_spectral* variants cannot render it)"
            )
        if requested.startswith("llvm") and not llvm:
            raise VariantError(f"variant {requested!r} needs libLLVM: {_INSTALL_LLVM}")
        if requested.startswith("cuda") and not _cuda_usable():
            raise VariantError(f"variant {requested!r} needs an NVIDIA GPU and driver; none found")
        if not _try_set(requested):
            raise VariantError(
                f"variant {requested!r} is not available; choose one of: auto, "
                f"{', '.join(mi.variants())}"
            )
        _selected = requested
        return requested
    for name in SUPPORTED_VARIANTS:
        if name.startswith("cuda") and not _cuda_usable():
            continue
        if name.startswith("llvm") and not llvm:
            continue
        if _try_set(name):
            _selected = name
            return name
    raise VariantError(
        f"no usable Mitsuba variant: seahaze needs an NVIDIA GPU (cuda_ad_rgb) or libLLVM "
        f"(llvm_ad_rgb); {_INSTALL_LLVM}"
    )
