"""Makes the compiled core importable as ``<the add-on's package>._native`` (find_native), which the
package's __init__ does first: ``core`` imports it, with or without Blender."""

import contextlib
import ctypes
import importlib
import importlib.util
import os
import sys


@contextlib.contextmanager
def _passive_openmp_wait():
    """GCC's OpenMP (the core's loops and CHOLMOD's) reads its wait policy once, when the core loads
    it. By default its idle threads spin at every barrier, and on cores that other work shares (the
    artist's Blender draws while it bakes) they take the core from the thread that has work
    (bench/results/bake_busy.json; docs/measurements.md, "A bake beside a busy core"). Set only
    while the core loads and only when the user chose no policy: other add-ons never see it. An
    OpenMP runtime loaded before the core (Debian's Blender shares the system's) keeps its own."""
    if {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"} & os.environ.keys():
        yield
        return
    os.environ["OMP_WAIT_POLICY"] = "passive"
    _set_core_c_environment("OMP_WAIT_POLICY=passive")
    try:
        yield
    finally:
        del os.environ["OMP_WAIT_POLICY"]
        _set_core_c_environment("OMP_WAIT_POLICY=")


def _set_core_c_environment(assignment):
    """The Windows core's C runtime is msvcrt.dll (MinGW-w64's), which keeps a copy of the
    environment of its own: os.environ changes the process's and the UCRT's, and libgomp reads
    msvcrt's ("NAME=" removes NAME)."""
    if sys.platform == "win32":
        ctypes.cdll.msvcrt._putenv(assignment.encode())


def find_native():
    """Make the compiled core importable as ``<this package>._native``. The source tree and the
    legacy add-on zip carry it in this folder; Blender 4.2+ installs it from the extension's bundled
    wheel into the extensions' site-packages as ``modal_deform_native._native``."""
    name = f"{__package__}._native"
    if name in sys.modules:
        return
    with _passive_openmp_wait():
        if importlib.util.find_spec("._native", __package__) is not None:
            importlib.import_module(name)
            return
        if importlib.util.find_spec("modal_deform_native") is None:
            raise ImportError(
                f"{__package__}: the compiled core is missing: no {name} (source tree: run `make build`) "
                "and no modal_deform_native (installed from the extension's wheel)"
            )
        sys.modules[name] = importlib.import_module("modal_deform_native._native")
