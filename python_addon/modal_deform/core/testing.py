"""Generated test shapes (the Botsch–Sorkine benchmarks'): V (n, 3) float64, F (m, 3) int32.

    import modal_deform.core as mdc
    V, F = mdc.testing.bar(4, 4, 16)

They are the C++ core's own (cpp/mesh/primitives.h), which its tests use: one definition for C++,
Python tests and the benchmarks. Quads are split into two triangles with alternating diagonals.
"""

from .. import _native


def grid(nx, ny, width=1.0, height=1.0):
    """Flat grid of nx by ny quads (two triangles each) in the z = 0 plane, centred at 0."""
    return _native.grid(nx, ny, width, height)


def bumpy_plane(n, size=10.0, bumps=12, amplitude=1.0, seed=1):
    """Square n by n grid with Gaussian bumps (the Botsch–Sorkine bumpy plane)."""
    return _native.bumpy_plane(n, size, bumps, amplitude, seed)


def cylinder(around, along, radius=1.0, length=4.0):
    """Open tube along z from 0 to ``length``."""
    return _native.cylinder(around, along, radius, length)


def bar(nx, ny, nz, sx=1.0, sy=1.0, sz=4.0):
    """Closed surface of the box [0, sx] x [0, sy] x [0, sz], faces oriented outwards."""
    return _native.bar(nx, ny, nz, sx, sy, sz)
