"""One bake of a shared mesh at 15 modes + 52 derivatives with a 1k ghost, for bench/bake_busy.py: in
plain Python on the source tree's core, or in bpy on the core of the extension that
tests/blender/bpy_session.py installed (Blender's own NumPy and its OpenBLAS beside it). Prints
{"seconds": the bake's wall time, "stages": {stage: seconds}} as JSON on its last line.

    python bench/bake_once.py MESH [--threads]
    python tests/blender/bpy_session.py --extension ZIP bench/bake_once.py -- MESH [--threads]

With --threads, a thread samples every OpenBLAS in the process (the one under CHOLMOD, NumPy's when
it has its own) for its thread count while the bake runs, and the JSON has
"openblas_threads_seen": {library: the counts seen}: on 2 cores the core's OpenBLAS runs on one
thread inside CHOLMOD's calls and NumPy's keeps its own.
"""

import argparse
import contextlib
import ctypes
import importlib
import json
import pathlib
import sys
import threading
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
MESHES = ROOT.parent / "shared" / "meshes"
#: How OpenBLAS builds name their thread count: plain, 64-bit integer (NumPy 1's wheels), SciPy's
#: (NumPy 2's wheels).
THREAD_COUNT_NAMES = (
    "openblas_get_num_threads",
    "openblas_get_num_threads64_",
    "scipy_openblas_get_num_threads64_",
)
SAMPLE_SECONDS = 0.002


def core():
    """modal_deform.core: the installed extension's inside Blender, the source tree's outside."""
    try:
        import bpy  # noqa: F401 (only to tell whether this is Blender)
    except ImportError:
        sys.path.insert(0, str(ROOT / "python_addon"))
        return importlib.import_module("modal_deform.core")
    sys.path.insert(0, str(ROOT / "tests" / "blender"))
    from bpy_session import MODULE

    return importlib.import_module(f"{MODULE}.core")


def openblas_thread_counts():
    """{folder/file of each OpenBLAS mapped in this process: its function returning its thread count}."""
    np.dot(np.ones((64, 64)), np.ones((64, 64)))  # NumPy's BLAS is loaded
    with open("/proc/self/maps") as maps:
        paths = {
            line.split()[-1]
            for line in maps
            if len(line.split()) == 6 and "openblas" in line.rsplit("/", 1)[-1]
        }
    counts = {}
    for path in sorted(paths):
        library = ctypes.CDLL(path)
        name = next((n for n in THREAD_COUNT_NAMES if hasattr(library, n)), None)
        if name:
            counts["/".join(pathlib.Path(path).parts[-2:])] = getattr(library, name)
    return counts


class ThreadSampler:
    """While it lives, every SAMPLE_SECONDS, the thread count of each OpenBLAS: `seen` {library: set}."""

    def __init__(self):
        self.counts = openblas_thread_counts()
        self.seen = {library: set() for library in self.counts}
        self.done = threading.Event()
        self.thread = threading.Thread(target=self.sample)

    def sample(self):
        while not self.done.wait(SAMPLE_SECONDS):
            for library, count in self.counts.items():
                self.seen[library].add(count())

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exception):
        self.done.set()
        self.thread.join()


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("mesh", help="a file of the shared meshes")
    parser.add_argument(
        "--threads", action="store_true", help="sample the OpenBLAS thread counts during the bake"
    )
    arguments = parser.parse_args(
        sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    )
    mdc = core()
    V, F = mdc.read_mesh(str(MESHES / arguments.mesh))
    sampler = ThreadSampler() if arguments.threads else contextlib.nullcontext()
    start = time.perf_counter()
    with sampler:
        basis = mdc.bake(V, F, modes=15, derivatives=52, ghost=1000)
    result = {"seconds": time.perf_counter() - start, "stages": basis.timings}
    if arguments.threads:
        result["openblas_threads_seen"] = {
            library: sorted(seen) for library, seen in sampler.seen.items()
        }
    print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
