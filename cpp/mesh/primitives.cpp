#include "mesh/primitives.h"

#include <array>
#include <cmath>
#include <vector>

#include "util/errors.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

void require_positive(int count, const char* name) {
  if (count < 1) throw InputError(message(name, ": needs at least 1, got ", count));
}

// Appends quad (a, b, c, d) (counter-clockwise) as two triangles; `flip` picks the other diagonal.
void add_quad(std::vector<int>& faces, int a, int b, int c, int d, bool flip) {
  if (flip)
    faces.insert(faces.end(), {a, b, d, b, c, d});
  else
    faces.insert(faces.end(), {a, b, c, a, c, d});
}

}  // namespace

TriangleMesh grid(int nx, int ny, double width, double height) {
  require_positive(nx, "nx");
  require_positive(ny, "ny");
  std::vector<double> positions;
  std::vector<int> faces;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      positions.insert(positions.end(),
                       {width * (double(i) / nx - 0.5), height * (double(j) / ny - 0.5), 0.0});
  auto at = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      add_quad(faces, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), (i + j) % 2 == 1);
  return mesh_from_buffers(positions, faces);
}

TriangleMesh bumpy_plane(int n, double size, int num_bumps, double amplitude, std::uint32_t seed) {
  TriangleMesh mesh = grid(n, n, size, size);
  std::uint32_t state = seed ? seed : 1;
  auto uniform = [&state] {  // xorshift32: the same bumps on every platform
    state ^= state << 13;
    state ^= state >> 17;
    state ^= state << 5;
    return state / 4294967296.0;
  };
  for (int b = 0; b < num_bumps; ++b) {
    const double cx = size * (0.8 * uniform() - 0.4), cy = size * (0.8 * uniform() - 0.4);
    const double height = amplitude * (0.5 + 0.5 * uniform());
    const double radius = size * (0.04 + 0.06 * uniform());
    for (Eigen::Index v = 0; v < mesh.V.rows(); ++v) {
      const double dx = mesh.V(v, 0) - cx, dy = mesh.V(v, 1) - cy;
      mesh.V(v, 2) += height * std::exp(-(dx * dx + dy * dy) / (2 * radius * radius));
    }
  }
  return mesh;
}

TriangleMesh cylinder(int n_around, int n_along, double radius, double length) {
  if (n_around < 3) throw InputError(message("n_around: needs at least 3, got ", n_around));
  require_positive(n_along, "n_along");
  std::vector<double> positions;
  std::vector<int> faces;
  for (int j = 0; j <= n_along; ++j)
    for (int i = 0; i < n_around; ++i) {
      const double angle = 2 * kPi * i / n_around;
      positions.insert(positions.end(),
                       {radius * std::cos(angle), radius * std::sin(angle), length * j / n_along});
    }
  auto at = [n_around](int i, int j) { return j * n_around + i % n_around; };
  for (int j = 0; j < n_along; ++j)
    for (int i = 0; i < n_around; ++i)
      add_quad(faces, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), (i + j) % 2 == 1);
  return mesh_from_buffers(positions, faces);
}

TriangleMesh bar(int nx, int ny, int nz, double sx, double sy, double sz) {
  require_positive(nx, "nx");
  require_positive(ny, "ny");
  require_positive(nz, "nz");
  const std::array<int, 3> cells{nx, ny, nz};
  const std::array<double, 3> sizes{sx, sy, sz};
  // Lattice points on the surface of the box get consecutive indices.
  std::vector<int> index((nx + 1) * (ny + 1) * (nz + 1), -1);
  auto lattice = [&](const std::array<int, 3>& p) {
    return (p[2] * (ny + 1) + p[1]) * (nx + 1) + p[0];
  };
  std::vector<double> positions;
  auto vertex = [&](const std::array<int, 3>& p) {
    int& id = index[lattice(p)];
    if (id < 0) {
      id = static_cast<int>(positions.size() / 3);
      for (int a = 0; a < 3; ++a) positions.push_back(sizes[a] * p[a] / cells[a]);
    }
    return id;
  };
  std::vector<int> faces;
  for (int axis = 0; axis < 3; ++axis) {
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;  // e_b x e_c = e_axis
    for (int side = 0; side < 2; ++side)
      for (int v = 0; v < cells[c]; ++v)
        for (int u = 0; u < cells[b]; ++u) {
          std::array<std::array<int, 3>, 4> corners;
          const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            corners[k][axis] = side * cells[axis];
            corners[k][b] = u + du[k];
            corners[k][c] = v + dv[k];
          }
          int q[4];
          for (int k = 0; k < 4; ++k) q[k] = vertex(corners[k]);
          const bool flip = (u + v) % 2 == 1;
          if (side == 1)
            add_quad(faces, q[0], q[1], q[2], q[3], flip);
          else  // the face at the low side points the other way
            add_quad(faces, q[0], q[3], q[2], q[1], !flip);
        }
  }
  return mesh_from_buffers(positions, faces);
}

}  // namespace modal_deform
