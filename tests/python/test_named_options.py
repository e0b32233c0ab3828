"""The options, their defaults and the statistics the native core defines once (cpp/bake/bake.h's
BakeOptions, cpp/solve/full_solver.h's FullSolveOptions and the stats tables beside them): the
Python API's defaults and the native calls' keywords come from there, and the stats keep the names
the API documents."""
import inspect

import numpy as np
import pytest

import modal_deform.core as mdc
from modal_deform import _native

# Options whose Python default is None (an empty array natively).
ARRAYS = {"stiffness_weights", "region", "held"}


@pytest.fixture(scope="module")
def tube():
    V, F = mdc.testing.cylinder(12, 8, radius=1.0, length=3.0)
    handles = [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 3 - 1e-9)]
    turned = np.eye(4)
    turned[:3, 3] = [0.3, 0.0, 0.2]
    return V, F, handles, [np.eye(4), turned]


def defaults(function):
    return {name: p.default for name, p in inspect.signature(function).parameters.items()}


@pytest.mark.parametrize("function, options", [(mdc.bake, mdc.BAKE_OPTIONS), (mdc.solve_full, mdc.FULL_SOLVE_OPTIONS)])
def test_the_python_defaults_are_the_native_ones(function, options):
    python = defaults(function)
    assert set(options) <= set(python)
    for name, default in options.items():
        if name in ARRAYS:
            assert python[name] is None and len(default) == 0, name
        else:
            assert python[name] == default, name
    assert mdc.PROXY_ABOVE == mdc.BAKE_OPTIONS["proxy_above"] and mdc.PROXY == mdc.BAKE_OPTIONS["proxy"]
    assert mdc.FULL_SOLVE_MAX_ITERATIONS == mdc.FULL_SOLVE_OPTIONS["max_iterations"]
    refine = defaults(mdc.ReducedSolver.refine)
    assert refine["tolerance"] == mdc.FULL_SOLVE_OPTIONS["tolerance"]
    assert refine["max_iterations"] == mdc.FULL_SOLVE_OPTIONS["max_iterations"]


def test_the_native_calls_take_options_by_name_only(tube):
    V, F, handles, transforms = tube
    with pytest.raises(ValueError, match="bake: mode is not an option"):
        _native.bake(V, F, mode=3)
    with pytest.raises(ValueError, match="solve_full: tol is not an option"):
        _native.solve_full(V, F, [h.astype(np.int32) for h in handles], transforms, np.ones(2), 100.0, tol=1e-3)
    with pytest.raises(ValueError, match="energy"):
        _native.bake(V, F, energy="springs")
    # An option left out keeps its default: the same basis as with every default given.
    given = {k: v for k, v in mdc.BAKE_OPTIONS.items() if k not in ARRAYS}
    given.update(modes=10, derivatives=5, ghost=50)
    a = _native.bake(V, F, modes=10, derivatives=5, ghost=50)
    b = _native.bake(V, F, **given)
    assert np.array_equal(a.vectors, b.vectors) and a.max_stiffness == mdc.BAKE_OPTIONS["max_stiffness"]


def test_the_stats_keep_their_documented_names(tube):
    V, F, handles, transforms = tube
    X, stats = mdc.solve_full(V, F, handles, transforms, stiffness=100.0, max_iterations=3)
    assert X.shape == V.shape
    assert set(stats) == {"steps", "iterations", "energy", "converged", "gradient_norm", "gradient_scale",
                          "factorizations", "initial_energy", "relaxed_vertices", "seconds", "stalled", "history"}
    assert stats["history"]
    for it in stats["history"]:
        assert set(it) == {"model", "shift", "step", "guarded", "ratio", "cg_iterations", "progress", "energy",
                           "gradient_norm"}
        assert it["model"] in ("exact", "projected")
    assert stats["history"][-1]["energy"] == stats["energy"]
    solver = mdc.ReducedSolver(mdc.bake(V, F, modes=10, derivatives=5, ghost=50), handles, stiffness=100.0)
    solver.set_transforms(transforms)
    assert set(solver.solve(max_iterations=2)) == {"iterations", "energy", "converged", "ms", "evaluations",
                                                    "gradient_norm", "stalled", "line_search_failures"}
