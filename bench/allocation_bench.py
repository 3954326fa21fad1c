"""make bench: heap allocations per compiled evaluation (issue 26: "remove the waste ... heap allocations in the hot
path"). A compiled evaluation should allocate nothing once its buffers are sized (robotdyn/kernels/common.hpp); a
temporary Eigen object in a kernel costs a malloc and a free on every call of a simulation's right-hand side.

How: a 20-line malloc counter (C, compiled here with the system's C compiler) is preloaded into a child Python
process, which counts the mallocs made inside ``Evaluator.profile`` (every part of an evaluation, timed ``repeat``
times, all in C++) at two repeat counts; the difference over the extra repeats is the allocations per repeat of all
the profile's parts together (the evaluation, the right-hand side with the pull-back, and their parts again). The
Python binding's own allocations (argument conversion) happen once per profile call and cancel out. This is a
benchmark, not a test: it asserts nothing, and it skips itself without a C compiler.

    python bench/allocation_bench.py
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

COUNTER = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stddef.h>
static long count = 0;
static int on = 0;
static void* (*real_malloc)(size_t) = 0;
void* malloc(size_t n) {
  if (!real_malloc) real_malloc = (void* (*)(size_t))dlsym(RTLD_NEXT, "malloc");
  if (on) ++count;
  return real_malloc(n);
}
long robotdyn_malloc_count(void) { return count; }
void robotdyn_malloc_counting(int o) { on = o; }
"""

CHILD = r"""
import ctypes, sys
import numpy as np
sys.path.insert(0, {bench!r})
import robotdyn
from robotdyn.fast.dispatch import compiled_model
from robotdyn.robots import module
lib = ctypes.CDLL({lib!r})
lib.robotdyn_malloc_count.restype = ctypes.c_long
for name in {robots!r}:
    robot = robotdyn.load(name)
    fast = compiled_model(robot)
    traj = next(iter(module(name).SCENARIOS.values())).run(robot, t_end=1.0, progress=False)
    q, nu = np.ascontiguousarray(traj.q[-1]), np.ascontiguousarray(traj.nu[-1])
    fast.compute(q, nu)
    counts = []
    for repeat in (10, 210):
        fast.ev.profile(q, nu, repeat, 1.0)  # buffers sized
        lib.robotdyn_malloc_counting(1)
        start = lib.robotdyn_malloc_count()
        fast.ev.profile(q, nu, repeat, 1.0)
        counts.append(lib.robotdyn_malloc_count() - start)
        lib.robotdyn_malloc_counting(0)
    dcounts = []  # the derivative set (derivatives_seconds: the set and one evaluation, repeated in C++)
    tau = np.zeros(len(robot.motors))
    try:
        fast.ev.derivatives(q, nu, tau)
    except Exception:  # (a state the compiled derivatives do not serve: no count)
        dcounts = None
    for repeat in (10, 210) if dcounts is not None else ():
        fast.ev.derivatives_seconds(q, nu, tau, repeat)
        lib.robotdyn_malloc_counting(1)
        start = lib.robotdyn_malloc_count()
        fast.ev.derivatives_seconds(q, nu, tau, repeat)
        dcounts.append(lib.robotdyn_malloc_count() - start)
        lib.robotdyn_malloc_counting(0)
    deriv = f"{{(dcounts[1] - dcounts[0]) / 200:>10.1f}}" if dcounts else f"{{'-':>10}}"
    print(f"{{name:<20}} {{(counts[1] - counts[0]) / 200:>8.2f}} {{deriv}}")
"""


def allocation_bench(robots=("quasimoro", "linkage_suspension", "mmr12_eod", "omni_caster", "adaptable_wheel")) -> None:
    """Print the heap allocations (mallocs) per repeat of Evaluator.profile's parts, per robot."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None or sys.platform != "linux":
        print("\nheap allocations per evaluation: skipped (needs Linux and a C compiler)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        src, lib = Path(tmp) / "count.c", Path(tmp) / "libcount.so"
        src.write_text(COUNTER)
        subprocess.run([cc, "-O2", "-shared", "-fPIC", "-o", str(lib), str(src), "-ldl"], check=True)
        code = CHILD.format(bench=str(Path(__file__).resolve().parent), lib=str(lib), robots=tuple(robots))
        env = {**os.environ, "LD_PRELOAD": str(lib)}
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    print("\nheap allocations (mallocs) per repeat of all of Evaluator.profile's parts (evaluation, right-hand side "
          "with the pull-back, and each part again; C++ only), and per derivative set (Evaluator.derivatives_seconds: "
          "the set and one evaluation, C++ only; most of it the outputs' own matrices):")
    print(f"{'robot':<20} {'profile':>8} {'derivs':>10}")
    print(out.stdout.rstrip() if out.returncode == 0 else f"  failed: {out.stderr.strip().splitlines()[-1:]}")


if __name__ == "__main__":
    allocation_bench()
