// Generated test shapes: the grids, tubes and bars of the Botsch–Sorkine deformation benchmarks.
//
// Quads are split into two triangles with alternating diagonals, so the meshes have no preferred
// direction.
#pragma once

#include <cstdint>

#include "mesh/triangle_mesh.h"

namespace modal_deform {

// A flat grid of nx by ny quads in the z = 0 plane, width by height, centred at the origin.
TriangleMesh grid(int nx, int ny, double width, double height);

// A square grid (n by n quads, side `size`) with `num_bumps` Gaussian bumps of height up to
// `amplitude` at pseudo-random places fixed by `seed`.
TriangleMesh bumpy_plane(int n, double size, int num_bumps, double amplitude,
                         std::uint32_t seed = 1);

// An open tube along z from 0 to `length`: n_around quads around, n_along along.
TriangleMesh cylinder(int n_around, int n_along, double radius, double length);

// The closed surface of a box [0, sx] x [0, sy] x [0, sz] with nx, ny, nz quads along its edges,
// faces oriented outwards.
TriangleMesh bar(int nx, int ny, int nz, double sx, double sy, double sz);

}  // namespace modal_deform
