#include "reduction/basis.h"

#include <cmath>

#include "util/errors.h"

namespace modal_deform {
namespace {

void require(bool condition, const std::string& what) {
  if (!condition) throw InputError("basis: " + what);
}

template <typename Matrix>
void require_finite(const Matrix& matrix, const char* name) {
  require(matrix.allFinite(), message(name, " has non-finite entries"));
}

}  // namespace

void validate_basis(const Basis& b) {
  const Eigen::Index n = b.rest.rows(), r = b.vectors.cols(), g = b.ghost_vertices.rows();
  require(n > 0, "rest has no vertices");
  require(r > 0, "vectors has no columns");
  require(b.mass.size() == n, message("mass has ", b.mass.size(), " entries for ", n, " vertices"));
  require(b.vectors.rows() == 3 * n, message("vectors has ", b.vectors.rows(), " rows, expected ", 3 * n));
  require(
      0 <= b.num_rigid && b.num_rigid <= b.num_modes && b.num_modes <= r,
      message("num_rigid, num_modes out of order: rigid ", b.num_rigid, ", modes ", b.num_modes, ", dimension ", r));
  require(
      0 <= b.num_floppy && b.num_floppy <= b.num_modes - b.num_rigid,
      message("num_floppy is ", b.num_floppy, ", outside [0, ", b.num_modes - b.num_rigid, "] (the non-rigid modes)"));
  require(b.eigenvalues.size() == b.num_modes,
          message("eigenvalues has ", b.eigenvalues.size(), " entries for ", b.num_modes, " modes"));
  require(g > 0, "ghost_vertices is empty");
  require(b.ghost_faces.rows() > 0, "ghost_faces is empty");
  require(b.ghost_map.size() == n, message("ghost_map has ", b.ghost_map.size(), " entries for ", n, " vertices"));
  require(b.ghost_vectors.rows() == 3 * g && b.ghost_vectors.cols() == r,
          message("ghost_vectors is ", b.ghost_vectors.rows(), " by ", b.ghost_vectors.cols(), ", expected ", 3 * g,
                  " by ", r));
  require(std::isfinite(b.scale) && b.scale > 0, message("scale ", b.scale, " is not a positive number"));
  require(std::isfinite(b.bending) && b.bending >= 0 && std::isfinite(b.membrane) && b.membrane >= 0,
          "energy weights must be finite and non-negative");
  require(b.num_dropped >= 0, "num_dropped is negative");
  require_finite(b.rest, "rest");
  require_finite(b.mass, "mass");
  require((b.mass.array() >= 0).all(), "mass has negative entries");
  require_finite(b.vectors, "vectors");
  require_finite(b.eigenvalues, "eigenvalues");
  require_finite(b.ghost_vertices, "ghost_vertices");
  require_finite(b.ghost_vectors, "ghost_vectors");
  // The messages are formatted only for an offending entry: per entry they took 1.2 s at 100k vertices.
  for (Eigen::Index v = 0; v < n; ++v)
    if (b.ghost_map[v] < 0 || b.ghost_map[v] >= g)
      require(false, message("ghost_map[", v, "] = ", b.ghost_map[v], " is outside [0, ", g, ")"));
  for (Eigen::Index f = 0; f < b.ghost_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (b.ghost_faces(f, k) < 0 || b.ghost_faces(f, k) >= g)
        require(false, message("ghost_faces[", f, "] refers to ghost vertex ", b.ghost_faces(f, k), ", outside [0, ",
                               g, ")"));
}

}  // namespace modal_deform
