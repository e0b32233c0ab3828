"""Posing: the interactive reduced solver (paper section 5) and the full-space reference solve.

Both minimise, in the normalised frame (the model scaled to a longest bounding-box edge of 10,
scale s), the deformation energy plus the handle term

    μ Σ_h w_h Σ_{i∈h} s²m_i ‖s (x_i − (R_h x̄_i + t_h))‖²

with m_i the lumped vertex masses, (R_h, t_h) handle h's rigid 4×4 transform of its rest
positions (mesh units) and μ the pull. A handle is an array of vertex indices; a vertex may
belong to several handles (its pulls add up, so it settles between their targets in proportion to
their weights), but not twice to one. Vertices without mass (in no triangle) pull with zero
weight.
"""

import numpy as np

from .. import _native
from . import _arrays, _inputs, _options
from .bake import BAKE_OPTIONS

#: The most vertices ReducedSolver.refine takes: the size bake takes without a proxy.
REFINE_MAX_VERTICES = BAKE_OPTIONS["proxy_above"].default
#: The options of ReducedSolver (cpp/solve/reduced_solver.h), of its solve() and of solve_full
#: (cpp/solve/full_solver.h; Refine takes its tolerance and max_iterations): {name: Option}.
SOLVER_OPTIONS = _options.table(_native.REDUCED_SOLVER_OPTIONS)
SOLVE_OPTIONS = _options.table(_native.REDUCED_SOLVE_OPTIONS)
FULL_SOLVE_OPTIONS = _options.table(_native.FULL_SOLVE_OPTIONS)


def nearest_rigid(matrix, centre):
    """The rigid 4x4 transform closest to ``matrix`` (4x4, e.g. a scaled or sheared controller's)
    that takes ``centre`` (3,) where ``matrix`` does: what the solvers take for a handle.

    Rotation: the orthogonal polar factor of the 3x3 part (U Vᵀ of its SVD, a reflection turned
    into a rotation); translation: chosen so the handle's centre lands on matrix @ centre. Native:
    playback computes one per moving handle every frame.
    """
    M = _arrays.reals(matrix, "matrix")
    if M.shape != (4, 4):
        raise ValueError(f"matrix: expected a 4x4 matrix, got shape {M.shape}")
    return _native.nearest_rigid(M, _arrays.values(centre, "centre", 3))


def rigid_fit(rest, moved):
    """The rigid 4x4 transform T minimising Σ ‖T rest_i − moved_i‖² over the points ``rest`` and
    ``moved`` ((n, 3) each), float64: a handle's rigid part in a motion (Kabsch: the rotation from
    the SVD of the centred points' covariance, a reflection turned into a rotation)."""
    rest = np.asarray(rest, dtype=np.float64)
    moved = np.asarray(moved, dtype=np.float64)
    a, b = rest.mean(axis=0), moved.mean(axis=0)
    U, _, Vt = np.linalg.svd((moved - b).T @ (rest - a))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    T = np.eye(4)
    T[:3, :3] = U @ D @ Vt
    T[:3, 3] = b - T[:3, :3] @ a
    return T


class ReducedSolver(_inputs.InBasis):
    """BFGS in a baked basis: x = x̄ + U q, energy on the ghost, handles exact on the fine mesh.

    ``basis``: from ``mdc.bake`` (kept alive by the solver). ``handles``: list of vertex index
    arrays; ``weights``: one per handle (default 1). The solver starts at rest with every handle at
    its rest position; the inverse Hessian's warm start is computed here, once per handle set.
    Long calls release the GIL; one solver must not be used from two threads at once.
    """

    @_options.takes_options(SOLVER_OPTIONS)
    def __init__(self, basis, handles, weights=None, **options):
        basis = _inputs.basis(basis)
        handles = _inputs.handles(handles)
        weights = _inputs.weights(weights, len(handles))
        self._native = _native.ReducedSolver(basis._native, handles, weights, **options)
        self._basis = basis
        # What refine() solves on the full mesh: the same objective.
        options.pop("warm_start", None)
        self._problem = dict(handles=handles, weights=weights, **options)
        self._transforms = [np.eye(4)] * len(handles)

    @property
    def q(self):
        """The reduced coordinates (r,) float64 (a copy)."""
        return self._native.q

    def set_transforms(self, transforms):
        """One rigid 4x4 transform per handle (rotation and translation of its rest positions).

        Raises ValueError naming the handle whose matrix is not rigid (scaled, sheared,
        mirrored, or a last row other than 0 0 0 1). Cheap: O(r) per handle.
        """
        transforms = _inputs.transforms(transforms, self._native.num_handles)
        self._native.set_transforms(transforms)
        self._transforms = transforms

    @_options.takes_options(SOLVE_OPTIONS)
    def solve(self, **options):
        """BFGS iterations from the current state, until the Gill–Murray–Wright test holds (paper
        eq. 14) or the budget is spent (a frame's share of time). Returns
        {"iterations", "energy" (the objective), "converged", "ms", "evaluations",
        "gradient_norm", "stalled", "line_search_failures"}: "stalled" when the call ended
        unconverged because no step lowers the objective (the line search failed even from the
        initial inverse Hessian), which a caller must not mistake for a solution;
        "line_search_failures" counts the failed line searches. q and the inverse Hessian carry
        over to the next call.
        """
        return self._native.solve(**options)

    @_options.takes_options(
        FULL_SOLVE_OPTIONS,
        exclude=(
            "pull",
            "energy",
            "bending",
            "membrane",
            "stiffness_weights",
            "max_stiffness",
            "held",
        ),
    )
    def refine(self, F, initial=None, progress=None, **options):
        """Refine: the pose's exact minimum on the full mesh, by ``solve_full`` from a start.

        ``F`` (m, 3): the fine mesh's triangles (the basis keeps only its rest positions).
        ``initial`` (n, 3): where to start, by default the reduced pose ``positions()``; an
        animation passes the previous frame's refined answer. Same objective as ``solve``: the
        handles, weights, pull, energy (with the basis's material weights, painted ones too) and the current
        transforms; a region bake's outside stays exactly at rest (``solve_full``'s ``held``).
        ``progress(stage, fraction) -> bool`` is called from time to time (False
        cancels: ``Cancelled``). Returns (positions (n, 3) float64, stats) with the stats of
        ``solve_full`` ("initial_energy" is the objective at the start). When the solve from the
        start does not converge (it stalled at a kink, or spent ``max_iterations``), the solve from
        rest (in load steps) is run as well and its answer returned if it converged or is lower
        (stats["from_rest"] says so); iterations, factorisations, seconds and the history then
        count both solves, whichever answer is returned (the core's policy, cpp/solve/refine.h).

        The solve runs on the fine mesh, not on the proxy of a basis baked on one: the proxy's rest
        mesh is not kept, and a refined proxy pose carried back by the prolongation would lose the
        fine detail refining is for. A Newton step factors the full Hessian once, which needs less
        memory than the bake's factor and blocks of right-hand sides, so meshes up to
        ``REFINE_MAX_VERTICES`` (the size the bake takes without a proxy) are refined; denser ones are
        refused with a ValueError rather than risking the memory of the process.
        """
        n = self.num_vertices
        if n > REFINE_MAX_VERTICES:
            raise ValueError(
                f"refine: the mesh has {n} vertices; refining works on meshes of up to "
                f"{REFINE_MAX_VERTICES} (a full Newton solve of a denser one needs more memory than "
                f"is safe here)"
            )
        start = (
            self.positions().astype(np.float64)
            if initial is None
            else _arrays.vertices(initial, "initial")
        )
        if start.shape != (n, 3):
            raise ValueError(f"initial: expected shape ({n}, 3), got {start.shape}")
        basis, problem = self._basis, self._problem
        # A region bake's outside stays exactly at rest (where the reduced pose left it).
        held = np.setdiff1d(np.arange(n), basis.region) if len(basis.region) else None
        return _on_full_mesh(
            _native.refine,
            basis.rest,
            F,
            self._transforms,
            initial=start,
            progress=progress,
            bending=basis.bending,
            membrane=basis.membrane,
            stiffness_weights=basis.stiffness_weights,
            max_stiffness=basis.max_stiffness,
            held=held,
            **problem,
            **options,
        )

    def objective(self, q):
        """The objective f(q) (ghost energy plus handle term, normalised frame) and its gradient
        (r,) at any q (r,), for the current transforms; the solver's state is left alone."""
        return self._native.objective(_arrays.values(q, "q", self.dimension))

    def reset(self):
        """Back to rest (q = 0) and the initial inverse Hessian; the transforms stay."""
        self._native.reset()


@_options.takes_options(FULL_SOLVE_OPTIONS)
def solve_full(V, F, handles, transforms, weights=None, initial=None, progress=None, **options):
    """The reference: Newton's method on the full mesh for the reduced solver's objective.

    V (n, 3), F (m, 3): the rest mesh; handles, transforms, weights, pull, energy as for
    ReducedSolver, the material as for ``bake``. From rest, large motions
    are taken in load steps (the first turning each handle by at most 30° and moving its centre by
    at most a tenth of the bounding-box diagonal, later ones longer or shorter as the previous
    converged fast or slowly); with ``initial`` (n, 3) the solve starts there in one step
    (Refine; an animation passes the previous frame's answer). Each Newton iteration solves with the
    Hessian shifted by a multiple of the mass matrix, the shift adapted to how well the step
    predicted the decrease: by conjugate gradients preconditioned by the last factorisation when
    they converge fast, else by factoring it anew (see cpp/solve/shifted_newton.h). Stops when the
    gradient norm is below ``tolerance`` times its value at rest (or at ``initial``, if larger), or after
    ``max_iterations`` Newton iterations in all. ``progress(stage, fraction) -> bool`` is called
    about every 0.1 s (False cancels: ``Cancelled``). Returns the pair (positions (n, 3) float64,
    stats) with stats = {"steps", "iterations",
    "energy", "converged", "gradient_norm", "gradient_scale", "factorizations", "seconds",
    "initial_energy", "relaxed_vertices", "stalled", "history"}. "relaxed_vertices": with ``initial``,
    the vertices of edges it stretched beyond three times their rest length (a reduced pose's fins
    and needles, which the ghost does not see) relaxed on their own before Newton's iterations. A solve that did not converge says so in "converged";
    only a converged one is a reference. "stalled": it stopped because the objective no longer
    decreased. "history": one dict per Newton iteration with "model" ("projected" or "exact": the
    Hessian the step solved with), "shift" (τ), "step" (the line search's α, above 1 when a full
    step was extended; 0 when it found no decrease), "guarded" (α < 1 only because longer steps
    turned a triangle over), "ratio" (the decrease over the model's, at α ≤ 1), "cg_iterations" (conjugate gradient iterations of the step; 0: a new
    factorisation solved it), "progress", "energy" and "gradient_norm" after it.
    """
    return _on_full_mesh(
        _native.solve_full,
        V,
        F,
        transforms,
        handles=handles,
        weights=weights,
        initial=initial,
        progress=progress,
        **options,
    )


def _on_full_mesh(native, V, F, transforms, *, handles, weights, initial, progress, **options):
    """``native`` (the core's solve_full or refine) called with solve_full's arguments, the arrays
    checked; the core checks the options."""
    V, F = _arrays.vertices(V), _arrays.faces(F)
    handles = _inputs.handles(handles)
    if options.get("held") is not None:
        options["held"] = _arrays.indices(options["held"], "held")
    if options.get("stiffness_weights") is not None:
        options["stiffness_weights"] = _arrays.stiffness_weights(
            options["stiffness_weights"], len(V)
        )
    if progress is not None and not callable(progress):
        raise ValueError(f"progress: expected a callable or None, got {type(progress).__name__}")
    return native(
        V,
        F,
        handles,
        _inputs.transforms(transforms, len(handles)),
        _inputs.weights(weights, len(handles)),
        initial=None if initial is None else _arrays.vertices(initial, "initial"),
        progress=progress,
        **options,
    )
