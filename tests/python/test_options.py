"""The options the native core declares once (cpp/util/option.h tables) reach the Python API as
explicit keyword-only parameters with the core's defaults, and the core checks their values."""

import inspect
import warnings

import numpy as np
import pytest

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def tube():
    V, F = mdc.testing.cylinder(12, 8, radius=1.0, length=3.0)
    handles = [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 3 - 1e-9)]
    return V, F, handles, mdc.bake(V, F, modes=10, derivatives=5, ghost=50)


@pytest.mark.parametrize(
    "function, table",
    [
        (mdc.bake, mdc.BAKE_OPTIONS),
        (mdc.solve_full, mdc.FULL_SOLVE_OPTIONS),
        (mdc.ReducedSolver, mdc.SOLVER_OPTIONS),
        (mdc.ReducedSolver.solve, mdc.SOLVE_OPTIONS),
        (mdc.Simulation, mdc.SIMULATION_OPTIONS),
        (mdc.DiscreteShells, mdc.MATERIAL_OPTIONS),
    ],
)
def test_signatures_show_every_option_with_the_core_default(function, table):
    parameters = inspect.signature(function).parameters
    doc = (function.__init__ if inspect.isclass(function) else function).__doc__
    for name, option in table.items():
        assert parameters[name].kind == inspect.Parameter.KEYWORD_ONLY, name
        assert parameters[name].default == option.default, name
        assert f"{name}={option.default!r}: {option.doc}" in doc, name
    assert "**" not in str(inspect.signature(function))


def test_one_pull_and_one_max_stiffness():
    pulls = {
        t["pull"].default
        for t in (mdc.SOLVER_OPTIONS, mdc.SIMULATION_OPTIONS, mdc.FULL_SOLVE_OPTIONS)
    }
    assert pulls == {1000.0}
    assert (
        mdc.BAKE_OPTIONS["max_stiffness"]
        == mdc.FULL_SOLVE_OPTIONS["max_stiffness"]
        == mdc.MATERIAL_OPTIONS["max_stiffness"]
    )
    assert mdc.BAKE_OPTIONS["max_stiffness"].range_text() == "in [1, 10000]"


def test_stiffness_is_an_alias_of_pull(tube):
    V, F, handles, basis = tube
    with pytest.warns(DeprecationWarning, match="'stiffness' is now called 'pull'"):
        old = mdc.ReducedSolver(basis, handles, stiffness=250.0)
    new = mdc.ReducedSolver(basis, handles, pull=250.0)
    moved = np.eye(4)
    moved[:3, 3] = [0.1, 0.0, 0.2]
    for solver in (old, new):
        solver.set_transforms([np.eye(4), moved])
    q = np.linspace(-1, 1, basis.dimension) * 1e-3
    assert old.objective(q)[0] == new.objective(q)[0]
    with pytest.raises(TypeError, match="both 'pull' and its old name 'stiffness'"):
        mdc.ReducedSolver(basis, handles, stiffness=1.0, pull=2.0)


def test_the_core_names_the_option_it_refuses(tube):
    V, F, handles, basis = tube
    with pytest.raises(ValueError, match=r"modes: expected at least 1, got 0"):
        mdc.bake(V, F, modes=0)
    with pytest.raises(ValueError, match="modes: expected an integer, got 2.5"):
        mdc.bake(V, F, modes=2.5)
    for not_whole in (np.float32(3.9), np.float64(3.0)):
        with pytest.raises(ValueError, match="substeps: expected an integer"):
            mdc.Simulation(basis, handles, substeps=not_whole)
    with pytest.raises(ValueError, match="rotation_pairs: expected True or False, got 1"):
        mdc.bake(V, F, rotation_pairs=1)
    with pytest.raises(ValueError, match="energy"):
        mdc.bake(V, F, energy="springs")
    with pytest.raises(ValueError, match=r"pull: expected a value in \(0, 1e\+12\], got 0"):
        mdc.ReducedSolver(basis, handles, pull=0.0)
    with pytest.raises(ValueError, match=r"tolerance: expected a value in \(0, 1\), got 2"):
        mdc.ReducedSolver(basis, handles).solve(tolerance=2.0)
    with pytest.raises(ValueError, match=r"damping: expected a value in \[0, 1\]"):
        mdc.Simulation(basis, handles, damping=float("nan"))
    with pytest.raises(TypeError, match="unexpected keyword argument 'mode'"):
        mdc.bake(V, F, mode=3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        stats = mdc.ReducedSolver(basis, handles).solve(max_iterations=np.int64(3), budget_ms=None)
    assert stats["iterations"] <= 3
