"""Would looping over the levels instead of unrolling them pay for itself?

The ``physical`` kernels unroll their per-level work: each level's exponentials, table gather
and accumulation are written out once per level, so the kernel grows with the level count and
is compiled once per count. A symbolic loop over the levels, with each level's radiance and
transmittance in drjit local memory (``dr.alloc_local``), would hold that work once. This script
measures both forms on a model of the per-level work of a path's segments (three segments; per
level: the transmittance, a distance drawn from it, a table gather, the accumulation), 2^21
lanes, 11 levels: the kernel's operations, its compile time and its run time, warm.

Usage: python scripts/bench_level_loop.py
"""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

LEVELS = 11
SLOTS = 12
LANES = 1 << 21
SEGMENTS = 3
TEXELS = 4096


def segment_inputs(mi: Any, dr: Any, seed: float) -> tuple[Any, Any]:
    """A uniform number and a segment length (m) per lane, from ``seed``."""
    x = dr.arange(mi.Float, LANES) * 1e-3 + dr.opaque(mi.Float, seed)
    u = dr.fma(x, 0.618, 0.1) - dr.floor(dr.fma(x, 0.618, 0.1))
    return u, 50.0 + 2000.0 * u


def level_work(mi: Any, dr: Any, table: Any, sigma: Any, k: Any, u: Any, length: Any) -> tuple:
    """One level's work on a segment: its transmittance, a distance drawn in proportion to it,
    the table's value there, and what it adds (RGB)."""
    t = dr.exp(-sigma * length)
    mass = 1.0 - t
    s = -dr.log(dr.maximum(1.0 - u * mass, 1e-30)) / sigma
    v = dr.gather(mi.Float, table, mi.UInt32(dr.clip(s * 0.1, 0, TEXELS - 1)) * LEVELS + k)
    return t, mi.Color3f(v * mass, v * t, v)


def unrolled(mi: Any, dr: Any, table: Any, sigmas: np.ndarray, seed: float) -> list:
    sigma = [dr.opaque(mi.Float, float(s)) for s in sigmas]
    u, length = segment_inputs(mi, dr, seed)

    def body(i, res, att, length):
        for k in range(LEVELS):
            t, add = level_work(mi, dr, table, sigma[k], k, u, length)
            res[k] = res[k] + att[k] * add
            att[k] = att[k] * t
        return i + 1, res, att, length * 0.5

    start = (mi.UInt32(0), [mi.Color3f(0.0) for _ in range(LEVELS)], [mi.Float(1.0)] * LEVELS)
    _, res, _, _ = dr.while_loop((*start, length), lambda i, *_: i < SEGMENTS, body)
    return [c for r in res for c in (r.x, r.y, r.z)]


def looped(mi: Any, dr: Any, table: Any, sigmas: np.ndarray, seed: float) -> list:
    sigma = mi.Float(np.asarray(sigmas, np.float32))
    count = dr.opaque(mi.UInt32, LEVELS)
    u, length = segment_inputs(mi, dr, seed)
    res = dr.alloc_local(mi.Color3f, SLOTS, mi.Color3f(0.0))
    att = dr.alloc_local(mi.Float, SLOTS, mi.Float(1.0))

    def body(i, res, att, length):
        def level(k, res, att):
            t, add = level_work(mi, dr, table, dr.gather(mi.Float, sigma, k), k, u, length)
            a = att[k]
            res[k] = res[k] + a * add
            att[k] = a * t
            return k + 1, res, att

        _, res, att = dr.while_loop((mi.UInt32(0), res, att), lambda k, *_: k < count, level)
        return i + 1, res, att, length * 0.5

    _, res, _, _ = dr.while_loop((mi.UInt32(0), res, att, length), lambda i, *_: i < SEGMENTS, body)
    return [c for k in range(SLOTS) for c in (res[k].x, res[k].y, res[k].z)]


def measure(form: Any, runs: int = 5) -> dict:
    """The largest kernel's operations and compile time (first run) and the median run time."""
    import drjit as dr
    import mitsuba as mi

    rng = np.random.default_rng(0)
    table = mi.Float(rng.random(TEXELS * LEVELS).astype(np.float32))
    sigmas = np.linspace(3.912 / 4000.0, 3.912 / 300.0, LEVELS)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    compile_ms, ops, execution = 0.0, 0, []
    for run in range(runs):
        dr.kernel_history()  # clear
        out = form(mi, dr, table, sigmas, float(run))
        dr.eval(out)
        dr.sync_thread()
        big = max(dr.kernel_history(), key=lambda h: h.get("operation_count", 0))
        if run == 0:
            compile_ms = big["backend_time"] + big["codegen_time"]
            ops = big["operation_count"]
        else:
            execution.append(big["execution_time"])
    dr.set_flag(dr.JitFlag.KernelHistory, False)
    return {"ops": ops, "compile_ms": compile_ms, "run_ms": statistics.median(execution)}


def main() -> None:
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    start = time.perf_counter()
    rows = {"unrolled": measure(unrolled), "looped": measure(looped)}
    for name, row in rows.items():
        print(
            f"{name}: {row['ops']} operations, compiled in {row['compile_ms']:.0f} ms, "
            f"runs in {row['run_ms']:.0f} ms (median of 4)"
        )
    ratio = rows["looped"]["run_ms"] / rows["unrolled"]["run_ms"]
    print(f"looped / unrolled run time: {ratio:.2f}x ({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
