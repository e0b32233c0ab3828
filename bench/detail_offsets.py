"""How fine detail should follow a proxy (issue 15): fixed in the rest frame, or turned with the
proxy triangle's local frame. Measured on a strongly bent detailed surface: a tube of radius 1.25
and length 10 with ripples (amplitude 0.06, about 5 samples per wavelength on the fine mesh, under
2 on the proxy: detail the proxy cannot hold), baked on a proxy of an eighth of its vertices and bent
by 90 and 120 degrees by its end rings (bench/shapes.py's rod poses). Both ways use the same
proxy basis and the same reduced solution q; only the placement of the detail differs:

    rest frame:     x_i = x̄_i + Σ_k w_ik (U q)_{v_ik}                 (what the core does)
    rotated frame:  x_i = Σ_k w_ik p_{v_ik} + R_t(q) (x̄_i − Σ_k w_ik p̄_{v_ik})

with p = p̄ + U q the posed proxy and R_t the rotation of the proxy triangle t's frame (edge,
normal). Reference: the full nonlinear solve of the fine mesh (Newton, mdc.solve_full), and the
fine mesh's own bake for comparison. RMS over all vertices relative to the bounding-box diagonal.

    PYTHONPATH=python_addon /usr/bin/python3 bench/detail_offsets.py
"""

import json
import sys

import numpy as np
import shapes

import modal_deform.core as mdc


def rippled_tube(around=128, along=200, amplitude=0.06, waves=(24, 40)):
    V, F = mdc.testing.cylinder(around, along, 1.25, 10.0)
    theta = np.arctan2(V[:, 1], V[:, 0])
    radial = amplitude * np.sin(waves[0] * theta) * np.sin(2 * np.pi * waves[1] * V[:, 2] / 10.0)
    V = V.copy()
    V[:, :2] *= (1 + radial / 1.25)[:, None]
    return V, F


def frames(P, tris):
    """Orthonormal frames (m, 3, 3) of triangles tris (m, 3) of points P: columns edge, normal × edge, normal."""
    a, b, c = P[tris[:, 0]], P[tris[:, 1]], P[tris[:, 2]]
    e = b - a
    n = np.cross(e, c - a)
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return np.stack([e, np.cross(n, e), n], axis=2)


def detail_offsets(basis, proxy_rest):
    """(n, 3): each fine vertex's rest offset from its point on the proxy."""
    w = basis.prolongation_weights.astype(np.float64)
    return basis.rest - np.einsum("nk,nkc->nc", w, proxy_rest[basis.prolongation_vertices])


def rotated_frame_positions(basis, proxy_rest, q):
    p = basis.num_basis_vertices
    P = proxy_rest + (basis.vectors.astype(np.float64) @ q).reshape(p, 3)
    tris, w = basis.prolongation_vertices, basis.prolongation_weights.astype(np.float64)
    base = np.einsum("nk,nkc->nc", w, P[tris])
    R = np.einsum("nij,nkj->nik", frames(P, tris), frames(proxy_rest, tris))
    return base + np.einsum("nij,nj->ni", R, detail_offsets(basis, proxy_rest))


def rms(X, Y, diagonal):
    return float(np.sqrt(np.mean(np.sum((X - Y) ** 2, axis=1))) / diagonal)


def main():
    V, F = rippled_tube()
    handles = shapes._rod_handles(V, 10.0)

    def bent(degrees):
        return [np.eye(4), shapes.rod_end(10.0, (0, 0), degrees * np.pi / 180, 0)]

    proxy = len(V) // 8
    basis = mdc.bake(V, F, modes=20, derivatives=47, ghost=1000, proxy=proxy, proxy_above=proxy)
    own = mdc.bake(V, F, modes=20, derivatives=47, ghost=1000, proxy=None)
    proxy_rest, _, _ = mdc.ghost_mesh(V, F, proxy)  # the proxy the bake made (the same call)
    assert len(proxy_rest) == basis.num_basis_vertices
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    results = {"vertices": len(V), "proxy_vertices": basis.num_basis_vertices, "poses": {}}
    for degrees in (90, 120):
        X_full, _ = mdc.solve_full(V, F, handles, bent(degrees))

        def converged(b):  # the animation to the pose in six frames, then to convergence
            solver = mdc.ReducedSolver(b, handles)
            for t in np.linspace(0, 1, 7)[1:]:
                solver.set_transforms(bent(t * degrees))
                solver.solve(max_iterations=50)
            solver.solve(max_iterations=500, tolerance=1e-9)
            return solver

        solver = converged(basis)
        X_rest = solver.positions().astype(np.float64)
        X_rotated = rotated_frame_positions(basis, proxy_rest, solver.q)
        X_own = converged(own).positions().astype(np.float64)
        results["poses"][f"bend {degrees}"] = figures = {
            "rest_frame": rms(X_rest, X_full, diagonal),
            "rotated_frame": rms(X_rotated, X_full, diagonal),
            "own_bake": rms(X_own, X_full, diagonal),
            "rest_frame_vs_own": rms(X_rest, X_own, diagonal),
            "rotated_frame_vs_own": rms(X_rotated, X_own, diagonal),
            # How far apart the two placements are, and how large the detail is.
            "between_frames": rms(X_rest, X_rotated, diagonal),
            "between_frames_max": float(
                np.linalg.norm(X_rest - X_rotated, axis=1).max() / diagonal
            ),
            "offsets": rms(detail_offsets(basis, proxy_rest), 0.0, diagonal),
        }
        print(f"bend {degrees}", json.dumps(figures), flush=True)
    json.dump(results, sys.stdout)
    print()


if __name__ == "__main__":
    main()
