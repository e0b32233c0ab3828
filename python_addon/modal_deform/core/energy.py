"""Deformation energies with their derivatives: value, gradient, Hessian, third derivative."""

import numpy as np

from .. import _native
from . import _arrays, _options

#: The shells energy's material, the native core's (cpp/energy/material.h): {name: Option}.
MATERIAL_OPTIONS = _options.table(_native.MATERIAL_OPTIONS)


class _Energy:
    """Methods shared by every energy. X, U, W: (n, 3) or (3n,) arrays."""

    def __init__(self, native):
        self._native = native

    @property
    def num_vertices(self):
        return self._native.num_vertices

    def _flat(self, X, name):
        return _arrays.positions(X, self._native.num_vertices, name)

    def value(self, X):
        """E(X): float."""
        return self._native.value(self._flat(X, "X"))

    def gradient(self, X):
        """∇E(X): (3n,) float64."""
        return self._native.gradient(self._flat(X, "X"))

    def hessian(self, X):
        """∇²E(X): scipy.sparse.csc_matrix (3n, 3n), symmetric."""
        return self._native.hessian(self._flat(X, "X"))

    def third(self, X, U, W):
        """∇³E(X)(U, W): (3n,) float64, the derivative of the Hessian along U applied to W."""
        return self._native.third(self._flat(X, "X"), self._flat(U, "U"), self._flat(W, "W"))


class Arap(_Energy):
    """As-rigid-as-possible energy (Sorkine & Alexa 2007) of the rest mesh (V, F), in length².

    Cotangent weights of the rest mesh, clamped at zero (edges whose opposite angles sum to more
    than 180 degrees drop out, so the rest state stays the minimum); one best rotation per vertex.
    ``hessian`` is exact at any X (the rotations' Schur complement); ``third`` raises ValueError:
    modal derivatives need the shells energy.
    """

    def __init__(self, V, F):
        super().__init__(_native.Arap(_arrays.vertices(V), _arrays.faces(F)))


class DiscreteShells(_Energy):
    """The discrete shells energy of Hildebrandt et al. 2011: E = α E_F + β (E_L + E_A).

    E_F sums the squared change of the dihedral angle over interior edges (weighted by
    3‖ē‖²/Ā_e), E_L the squared change of edge lengths (over ‖ē‖), E_A the squared change of
    triangle areas (over Ā); barred quantities are those of the rest mesh ``V``. ``bending`` is
    α and ``membrane`` β. The paper scales models to a longest bounding-box edge of 10 first.

    V: (n, 3) rest positions, F: (m, 3) triangles. Raises ValueError for an unusable mesh, a
    weight that is negative or not finite, or bad stiffness weights (naming the vertex). Degenerate rest triangles and zero-length rest edges
    have no terms; non-manifold edges bend as if their sheets were welded pairwise.
    """

    @_options.takes_options(MATERIAL_OPTIONS)
    def __init__(self, V, F, **material):
        super().__init__(_native.DiscreteShells(_arrays.vertices(V), _arrays.faces(F), **material))

    @property
    def term_counts(self):
        """{"edges": int, "triangles": int, "hinges": int}: the length, area and bending terms."""
        return self._native.term_counts

    def third_batch(self, X, Phi, pairs):
        """∇³E(X)(Φ_i, Φ_j) for each pair: (3n, p) float64, column k for (i, j) = pairs[k].

        Phi: (3n, c) columns (e.g. vibration modes); pairs: (p, 2) column indices in [0, c).
        """
        Phi = np.asfortranarray(Phi, dtype=np.float64)
        if Phi.ndim != 2 or Phi.shape[0] != 3 * self.num_vertices:
            raise ValueError(f"Phi: expected shape ({3 * self.num_vertices}, c), got {Phi.shape}")
        pairs = np.asarray(pairs)
        if pairs.size == 0:
            pairs = pairs.reshape(0, 2)
        if pairs.ndim != 2 or pairs.shape[1] != 2 or pairs.dtype.kind not in "iu":
            raise ValueError(
                f"pairs: expected a (p, 2) array of integer column indices, got shape "
                f"{pairs.shape} and dtype {pairs.dtype}"
            )
        return self._native.third_batch(self._flat(X, "X"), Phi, pairs.tolist())
