"""Fig. 7 analogue: the objective against iteration for one large pose taken in a single step from
rest, four ways on the same reduced problem (paper Fig. 7):

- Newton: Newton's method in q with the exact reduced Hessian, s² U_sᵀ ∇²E_ghost U_s (energy
  API) plus the handle term's (constant; from differences of the solver's exact gradient);
- BFGS, warm start: the interactive solver (initial inverse Hessian from the rest state);
- BFGS, cold start: the same solver with the identity as initial inverse Hessian;
- steepest descent.

Newton and steepest descent use SciPy's strong-Wolfe line search on ReducedSolver.objective
(halving the step to sufficient decrease where it finds no Wolfe step);
the BFGS runs are the solver itself, one iteration per call (its state carries over).
"""

import numpy as np
import scipy.optimize
import shapes

import modal_deform.core as mdc

ITERATIONS = 60
CASES = (("bar", "bend"), ("cylinder", "bend_twist"), ("bar", "bend_large"))
DIMENSION = (20, 47)  # modes (rigid motions included) and derivatives: 67 dimensions


class Problem:
    """The reduced solver's objective for one pose, with the exact reduced Hessian."""

    def __init__(self, basis, shape, transforms):
        self.solver = mdc.ReducedSolver(basis, shape.handles)
        self.solver.set_transforms(transforms)
        s = basis.scale
        self.ghost_energy = mdc.DiscreteShells(
            s * basis.ghost_vertices, basis.ghost_faces, basis.bending, basis.membrane
        )
        self.ghost_rest = s * basis.ghost_vertices.reshape(-1)
        self.ghost_vectors = s * np.asarray(basis.ghost_vectors)
        # The handle term is quadratic in q: its Hessian is exact from differences of its gradient.
        r = basis.dimension
        handle_gradient = lambda q: self.solver.objective(q)[1] - self.ghost_gradient(q)
        at_rest = handle_gradient(np.zeros(r))
        self.handle_hessian = np.column_stack([handle_gradient(e) - at_rest for e in np.eye(r)])

    def ghost_gradient(self, q):
        return self.ghost_vectors.T @ self.ghost_energy.gradient(
            self.ghost_rest + self.ghost_vectors @ q
        )

    def hessian(self, q):
        H = self.ghost_energy.hessian(self.ghost_rest + self.ghost_vectors @ q)
        H = self.ghost_vectors.T @ (H @ self.ghost_vectors) + self.handle_hessian
        return 0.5 * (H + H.T)

    def value(self, q):
        return self.solver.objective(q)[0]

    def gradient(self, q):
        return self.solver.objective(q)[1]


def descend(problem, direction):
    """Objective after each of up to ITERATIONS line-searched steps along direction(q, gradient),
    and the gradient norm at the end."""
    q = np.zeros(problem.solver.dimension)
    value, gradient = problem.solver.objective(q)
    trace = [value]
    for _ in range(ITERATIONS):
        p = direction(q, gradient)
        step, *_ = scipy.optimize.line_search(
            problem.value, problem.gradient, q, p, gradient, value, c2=0.9
        )
        if step is None:  # no Wolfe step found: backtrack to sufficient decrease alone (Armijo)
            step = next(
                (
                    a
                    for a in 0.5 ** np.arange(40)
                    if problem.value(q + a * p) <= value + 1e-4 * a * (gradient @ p)
                ),
                None,
            )
        if step is None:  # no decrease left at this precision
            break
        q = q + step * p
        value, gradient = problem.solver.objective(q)
        trace.append(value)
    return trace, float(np.linalg.norm(gradient))


def newton_direction(problem):
    def direction(q, gradient):
        H = problem.hessian(q)
        shift = 0.0
        while True:  # Hessian modification (Nocedal & Wright 3.4) where it is not positive definite
            try:
                L = np.linalg.cholesky(H + shift * np.eye(len(q)))
                break
            except np.linalg.LinAlgError:
                shift = max(2 * shift, 1e-8 * np.abs(np.diag(H)).max())
        return -scipy.linalg.cho_solve((L, True), gradient)

    return direction


def bfgs(basis, shape, transforms, warm):
    solver = mdc.ReducedSolver(basis, shape.handles, warm_start=warm)
    solver.set_transforms(transforms)
    value, gradient = solver.objective(solver.q)
    trace = [value]
    for _ in range(ITERATIONS):
        stats = solver.solve(max_iterations=1, tolerance=1e-15)
        if stats["iterations"] == 0:
            break
        trace.append(stats["energy"])
    return trace, float(np.linalg.norm(solver.objective(solver.q)[1]))


def run(quick=False):
    cases = []
    for name, pose_name in CASES:
        shape = shapes.make(
            name,
            **(
                {"bar": dict(nx=4, nz=30), "cylinder": dict(around=16, along=20)}[name]
                if quick
                else {}
            ),
        )
        basis = mdc.bake(shape.V, shape.F, *DIMENSION, ghost=1000)
        transforms = shape.pose(pose_name).at(1.0)
        problem = Problem(basis, shape, transforms)
        runs = {
            "Newton": descend(problem, newton_direction(problem)),
            "BFGS, warm start": bfgs(basis, shape, transforms, True),
            "BFGS, cold start": bfgs(basis, shape, transforms, False),
            "steepest descent": descend(problem, lambda q, gradient: -gradient),
        }
        traces = {method: trace for method, (trace, _) in runs.items()}
        cases.append(
            {
                "shape": name,
                "pose": pose_name,
                "vertices": len(shape.V),
                "dimension": basis.dimension,
                "ghost": len(basis.ghost_vertices),
                "minimum": min(min(t) for t in traces.values()),
                "traces": traces,
                "final_gradient_norms": {method: norm for method, (_, norm) in runs.items()},
            }
        )
        print(
            f"  {name} {pose_name}: "
            + ", ".join(f"{k} {len(t) - 1} it -> {t[-1]:.6g}" for k, t in traces.items()),
            flush=True,
        )
    parameters = {
        "cases": CASES,
        "modes_derivatives": DIMENSION,
        "iterations": ITERATIONS,
        "stiffness": mdc.solve.STIFFNESS,
        "line_search": "scipy.optimize.line_search (strong Wolfe, c2=0.9)",
    }
    return parameters, {"cases": cases}
