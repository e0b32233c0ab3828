"""The bake's linear algebra, generic in a stiffness K and lumped masses: vibration modes, rigid
motions, and the modal-derivative solves (paper eq. 13).

K is a (3n, 3n) symmetric positive semidefinite scipy.sparse matrix (an energy's Hessian at rest,
DOFs interleaved x0 y0 z0 x1 ...); mass holds the n vertex masses, M = diag(mass) ⊗ I₃. DOFs
with neither mass nor stiffness (unreferenced vertices) stay zero in every result.
"""

import numpy as np

from .. import _native
from . import _arrays


def _stiffness(K):
    """K as a float64 csc matrix with sorted, unique indices (what the native core reads)."""
    import scipy.sparse  # not at the top: Blender's own Python has NumPy but no SciPy

    if not scipy.sparse.issparse(K):
        raise ValueError(f"K: expected a scipy.sparse matrix, got {type(K).__name__}")
    K = scipy.sparse.csc_matrix(K, dtype=np.float64)
    if not K.has_canonical_format:
        K = K.copy()
        K.sum_duplicates()
    return K


def vibration_modes(K, mass, count, kernel=None):
    """The ``count`` lowest eigenpairs of K φ = λ M φ, rigid motions (λ = 0) included.

    With ``kernel`` (3n, z), M-orthonormal columns in the kernel of K such as rigid_motions, the
    ``count`` lowest eigenpairs whose modes are M-orthogonal to it: the flexible modes, without
    spending Lanczos iterations on the 6 zero modes of every component.
    Returns (eigenvalues (count,) ascending, modes (3n, count) M-orthonormal). Raises ValueError
    for bad input and RuntimeError when the eigensolver fails (for instance K is indefinite).
    """
    K = _stiffness(K)
    kernel = np.zeros((K.shape[0], 0)) if kernel is None else kernel
    return _native.vibration_modes(
        K, _arrays.values(mass, "mass"), int(count), _arrays.columns(kernel, K.shape[0], "kernel")
    )


def rigid_motions(V, labels, mass):
    """The 6 rigid motions of each component, M-orthonormal: (3n, 6c).

    V: (n, 3) positions; labels: (n,) component of each vertex in [-1, c), -1 for vertices
    outside every component (zero rows); mass: (n,). Columns 6k .. 6k+5 belong to component k:
    translations along x, y, z, then rotations about its principal axes through its centroid.
    """
    V = _arrays.vertices(V)
    return _native.rigid_motions(
        V, _arrays.labels(labels, len(V)), _arrays.values(mass, "mass", len(V))
    )


def solve_in_range(K, mass, Z, B):
    """Ψ (3n, p) with K Ψ = P B and Zᵀ M Ψ = 0.

    P projects B onto the range of K (Euclidean-orthogonal to its kernel); Z: (3n, z),
    M-orthonormal, spanning the kernel of K (e.g. rigid_motions); B: (3n, p) or (3n,).
    """
    K = _stiffness(K)
    return _native.solve_in_range(
        K,
        _arrays.values(mass, "mass"),
        _arrays.columns(Z, K.shape[0], "Z"),
        _arrays.columns(B, K.shape[0], "B"),
    )
