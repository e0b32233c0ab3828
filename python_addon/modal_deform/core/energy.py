"""Deformation energies with their derivatives: value, gradient, Hessian, third derivative."""
from .. import _native
from . import _arrays


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
