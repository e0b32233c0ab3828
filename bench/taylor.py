"""Fig. 9 analogue: the deformation energy and the objective (energy plus handle term) along a line
q(t) = t q* in the reduced space (q* the converged reduced pose, so t = 1 is the objective's
minimum on the fine mesh), evaluated (paper Fig. 9)

- on the fine mesh (the basis with the mesh itself as ghost): the exact reduced objective;
- by its second- and third-order Taylor expansions at rest: the deformation energy's
  ½ t² vᵀ∇²E v + ⅙ t³ ∇³E(v, v)·v with v = s U q* (energy API, normalised frame), plus the
  handle term, which is quadratic and taken exactly;
- on ghosts of 1k, 5k and 10k vertices (the bake's ghost construction, same basis).

Each curve's objective minimum on the line (bounded scalar minimisation) is reported and marked.
"""

import numpy as np
import scipy.optimize
import shapes
from table1 import with_ghost

import modal_deform.core as mdc

SHAPE, POSE = "bumpy_plane", "bend"
DIMENSION = (20, 47)
GHOSTS = (1000, 5000, 10000)
LINE = np.linspace(-0.25, 1.75, 201)


def objective_along(basis, shape, transforms, direction):
    """f(t q*) as a function of t."""
    solver = mdc.ReducedSolver(basis, shape.handles)
    solver.set_transforms(transforms)
    return lambda t: solver.objective(t * direction)[0]


def minimum(f):
    found = scipy.optimize.minimize_scalar(
        f, bounds=(LINE[0], LINE[-1]), method="bounded", options={"xatol": 1e-6}
    )
    return {"t": float(found.x), "value": float(found.fun)}


def run(quick=False):
    shape = shapes.make(SHAPE, n=40) if quick else shapes.make(SHAPE)
    ghosts = (100, 400, 1000) if quick else GHOSTS
    transforms = shape.pose(POSE).at(1.0)
    basis = mdc.bake(shape.V, shape.F, *DIMENSION, ghost=len(shape.V))
    solver = mdc.ReducedSolver(basis, shape.handles)
    solver.set_transforms(transforms)
    while not solver.solve(max_iterations=50, tolerance=1e-12)["converged"]:
        pass
    direction = solver.q
    objectives = {"fine mesh": objective_along(basis, shape, transforms, direction)}

    s = basis.scale
    energy = mdc.DiscreteShells(s * basis.rest, shape.F, basis.bending, basis.membrane)
    rest = s * basis.rest.reshape(-1)
    v = s * (np.asarray(basis.vectors, np.float64) @ direction)
    # The handle term is quadratic in t: exact from three samples of objective minus energy.
    samples = np.array([-1.0, 0.0, 1.0])
    handle_term = np.poly1d(
        np.polyfit(
            samples, [objectives["fine mesh"](t) - energy.value(rest + t * v) for t in samples], 2
        )
    )
    second = 0.5 * v @ (energy.hessian(rest) @ v)
    third = energy.third(rest, v, v) @ v / 6
    objectives["Taylor, 2nd order"] = lambda t: second * t**2 + handle_term(t)
    objectives["Taylor, 3rd order"] = lambda t: second * t**2 + third * t**3 + handle_term(t)
    for ghost in ghosts:
        coarse = with_ghost(basis, shape.F, ghost)
        objectives[f"ghost {len(coarse.ghost_vertices)}"] = objective_along(
            coarse, shape, transforms, direction
        )
    curves = {name: np.array([f(t) for t in LINE]) for name, f in objectives.items()}
    energies = {name: c - handle_term(LINE) for name, c in curves.items()}
    minima = {name: minimum(f) for name, f in objectives.items()}
    for name, m in minima.items():
        print(f"  {name}: objective minimum {m['value']:.5g} at t = {m['t']:.4f}", flush=True)
    parameters = {
        "shape": SHAPE,
        "vertices": len(shape.V),
        "pose": POSE,
        "modes_derivatives": DIMENSION,
        "dimension": basis.dimension,
        "ghosts": ghosts,
        "stiffness": mdc.solve.STIFFNESS,
        "line": "q(t) = t q*, q* the converged reduced pose on the fine mesh",
    }
    return parameters, {"t": LINE, "objective": curves, "energy": energies, "minima": minima}
