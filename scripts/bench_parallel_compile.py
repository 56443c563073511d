"""Does drjit compile two kernels at once when two threads ask? (docs/benchmarks.md, "How much
longer is a render with an empty kernel cache?")

Two kernels of about 3,000 operations each (new constants every run, so the kernel cache never
holds them) are built and evaluated one after the other, then each in its own Python thread;
then the same with both traced first and only evaluated in the threads. If the LLVM backend
compiled them in parallel, the threaded times would approach half the sequential ones on a
machine with two free CPUs.

Usage: python scripts/bench_parallel_compile.py [--ops 3000] [--seed N]
"""

from __future__ import annotations

import argparse
import random
import threading
import time
from typing import Any


def kernel(seed: int, ops: int) -> Any:
    """A kernel's worth of arithmetic on 100,000 lanes, its constants drawn from ``seed``."""
    import drjit as dr
    from drjit.llvm import Float

    rng = random.Random(seed)
    x = dr.arange(Float, 100_000) * 1e-5
    y = Float(x)
    for i in range(ops):
        c = rng.random()
        y = dr.fma(y, c, dr.sin(x * c + y * 0.001)) if i % 7 == 0 else y * c + x
    return y


def in_threads(jobs: list) -> float:
    """Wall seconds to run ``jobs`` (callables), each in its own thread."""
    start = time.perf_counter()
    threads = [threading.Thread(target=job) for job in jobs]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return time.perf_counter() - start


def report(what: str, sequential: float, threaded: float) -> None:
    print(f"{what}: one after the other {sequential:.2f} s, in two threads {threaded:.2f} s")


def main() -> None:
    import drjit as dr

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ops", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=random.SystemRandom().randrange(1 << 30))
    args = parser.parse_args()
    s, n = args.seed, args.ops

    start = time.perf_counter()
    for k in range(2):
        dr.eval(kernel(s + k, n))
    sequential = time.perf_counter() - start
    threaded = in_threads([lambda k=k: dr.eval(kernel(s + 2 + k, n)) for k in range(2)])
    report("built and evaluated", sequential, threaded)

    traced = [kernel(s + 4 + k, n) for k in range(2)]
    start = time.perf_counter()
    for y in traced:
        dr.eval(y)
    sequential = time.perf_counter() - start
    traced = [kernel(s + 6 + k, n) for k in range(2)]
    threaded = in_threads([lambda y=y: dr.eval(y) for y in traced])
    report("traced first, evaluated", sequential, threaded)


if __name__ == "__main__":
    main()
