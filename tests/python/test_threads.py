"""Threads on a shared machine without touching the caller's settings: the core's OpenMP waits
passively unless the user chose otherwise, and the process environment is as it was; the bake limits
the threads of the OpenBLAS under CHOLMOD only inside its own calls, so a NumPy that shares that
OpenBLAS (Debian's, in plain Python) keeps the threads its caller set, during the bake (in the
progress callback) and after it."""

import ctypes
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import modal_deform.core as mdc

ADDON_FOLDER = pathlib.Path(mdc.__file__).resolve().parents[2]


def import_in_fresh_python(**environment):
    """(what libgomp reports of its settings, OMP_WAIT_POLICY as Python sees it after the import)."""
    env = {
        key: value
        for key, value in os.environ.items()
        if key not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")
    }
    env.update(environment, OMP_DISPLAY_ENV="verbose")
    script = (
        f"import os, sys; sys.path.insert(0, {str(ADDON_FOLDER)!r}); import modal_deform.core; "
        "print(os.environ.get('OMP_WAIT_POLICY'))"
    )
    run = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True
    )
    return run.stderr, run.stdout.strip()


def test_openmp_waits_passively_and_the_environment_is_left_as_it_was():
    report, policy_after = import_in_fresh_python()
    assert "GOMP_SPINCOUNT = '0'" in report
    assert policy_after == "None"


def test_a_wait_policy_the_user_chose_is_kept():
    report, policy_after = import_in_fresh_python(OMP_WAIT_POLICY="active")
    assert "OMP_WAIT_POLICY = 'ACTIVE'" in report
    assert policy_after == "active"


def loaded_openblas():
    """The OpenBLAS library loaded in this process that CHOLMOD calls, or None: on Linux NumPy's,
    here shared with the core; on Windows the one the core bundles (its wheel, windows/windows.mk)."""
    if sys.platform == "win32":
        module_handle = ctypes.windll.kernel32.GetModuleHandleW
        module_handle.restype = ctypes.c_void_p
        handle = module_handle("modal_deform_openblas.dll")
        return ctypes.CDLL("modal_deform_openblas.dll", handle=handle) if handle else None
    with open("/proc/self/maps") as maps:
        paths = {line.split()[-1] for line in maps if "openblas" in line.rsplit("/", 1)[-1]}
    for path in sorted(paths):
        library = ctypes.CDLL(path)
        if hasattr(library, "openblas_get_num_threads") and hasattr(
            library, "openblas_set_num_threads"
        ):
            return library
    return None


def test_the_callers_openblas_threads_are_kept_during_and_after_the_bake():
    np.dot(np.ones((64, 64)), np.ones((64, 64)))  # NumPy's BLAS is loaded
    openblas = loaded_openblas()
    if openblas is None or (os.cpu_count() or 1) < 2:
        pytest.skip(
            "needs an OpenBLAS in this process and two cores, so that the bake would lower its threads"
        )
    callers = openblas.openblas_get_num_threads()
    openblas.openblas_set_num_threads(os.cpu_count())
    try:
        setting = openblas.openblas_get_num_threads()
        seen = []

        def progress(stage, fraction):
            seen.append(openblas.openblas_get_num_threads())
            return True

        mdc.bake(
            *mdc.testing.cylinder(14, 6, 0.5, 2.0),
            modes=12,
            derivatives=6,
            ghost=40,
            progress=progress,
        )
        assert seen and set(seen) == {setting}
        assert openblas.openblas_get_num_threads() == setting
    finally:
        openblas.openblas_set_num_threads(callers)
