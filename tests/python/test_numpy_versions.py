"""The core under the NumPy this Python has (make test: NumPy 1.24 on the in-tree build, NumPy 2.5 on
the installed cp313 wheel; bpy 4.2.0 brings NumPy 2.4 to the cp311 wheel).

Arrays cross into the core either as views (Eigen::Ref) or copied into Eigen matrices (a list of
handles, q, an initial pose). The copy goes through NumPy's C API table, whose layout NumPy 2
changed: a core built with pybind11 older than 2.12 called an empty slot there and the process (an
artist's Blender) died at the first Solve. Each path runs in a child process, so a crash fails the
test with its signal instead of ending the test run."""

import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

COPIED_INTO_THE_CORE = {
    "handles and q": """
        basis = mdc.bake(V, F, modes=8, derivatives=4, ghost=60)
        solver = mdc.ReducedSolver(basis, handles, pull=100.0)
        solver.set_transforms(transforms)
        solver.solve(max_iterations=5)
        value, gradient = solver.objective(solver.q)
        assert np.isfinite(value) and gradient.shape == solver.q.shape
    """,
    "an initial pose": """
        X, stats = mdc.solve_full(V, F, handles, transforms, pull=100.0, initial=V.copy(), max_iterations=3)
        assert np.isfinite(X).all()
    """,
}


@pytest.mark.parametrize("path", COPIED_INTO_THE_CORE)
def test_arrays_copied_into_the_core(path):
    script = (
        textwrap.dedent("""
        import numpy as np
        import modal_deform.core as mdc
        V, F = mdc.testing.cylinder(8, 6, radius=1.0, length=3.0)
        handles = [np.flatnonzero(V[:, 2] < 1e-9).astype(np.int32), np.flatnonzero(V[:, 2] > 3 - 1e-9)]
        turn = np.eye(4)
        turn[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
        transforms = [np.eye(4), turn]
    """)
        + textwrap.dedent(COPIED_INTO_THE_CORE[path])
        + "print('OK')\n"
    )
    result = subprocess.run(
        [sys.executable, "-X", "faulthandler", "-c", script],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if result.returncode < 0:
        pytest.fail(
            f"NumPy {np.__version__}: the core crashed with {signal.Signals(-result.returncode).name} "
            f"({path}):\n{result.stderr[-3000:]}"
        )
    assert result.returncode == 0 and "OK" in result.stdout, result.stderr[-3000:]
