"""Time the physical mode's one pass in-process, compiled kernels excluded: the clean image and
every level of a scene, against one level and against Mitsuba's clean pass alone.

Each figure is the best of three calls after one untimed call (which compiles or loads the
kernels for that image size and sample count). Geometry, scene loading and writing are not
included: see scripts/bench_one_pass.py for whole ``seahaze render`` runs.

Usage: python scripts/bench_pass_ratios.py SCENE.yaml WxH SPP
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any


def best_of(call: Callable[[], Any], runs: int = 3) -> tuple[float, Any]:
    """Best wall time (s) of ``runs`` calls after one untimed call, and the last result."""
    out = call()
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        out = call()
        times.append(time.perf_counter() - start)
    return min(times), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("res", help="WxH, e.g. 640x360")
    parser.add_argument("spp", type=int)
    args = parser.parse_args()
    from seahaze.render.engine import open_session
    from seahaze.render.physical import PhysicalRenderer
    from seahaze.sceneio import load_scene
    from seahaze.spec import with_overrides
    from seahaze.visibility import channel_extinction

    width, height = (int(v) for v in args.res.split("x"))
    spec, _ = load_scene(args.scene)
    spec = with_overrides(spec, resolution=(width, height), spp=args.spp)
    session = open_session(spec)
    haze = spec.haze
    sigmas = [channel_extinction(v, haze.threshold, haze.extinction_spectrum) for v in haze.levels]
    renderer = PhysicalRenderer(session.loaded, spec)
    all_s, all_out = best_of(lambda: renderer.render(sigmas, haze.albedo, haze.g, args.spp, 7))
    one_s, one_out = best_of(lambda: renderer.render(sigmas[:1], haze.albedo, haze.g, args.spp, 7))
    clean_s, _ = best_of(session.render_clean)
    print(
        f"{width}x{height}, {args.spp} spp, {len(sigmas)} levels: one pass {all_s:.2f} s "
        f"(tables {all_out.table_seconds:.2f} s); one level {one_s:.2f} s (table "
        f"{one_out.table_seconds:.2f} s); Mitsuba's clean pass {clean_s:.2f} s; "
        f"all/one {all_s / one_s:.2f}, all/clean {all_s / clean_s:.2f}"
    )


if __name__ == "__main__":
    main()
