#include "basis/basis.h"

#include <cmath>
#include <limits>
#include <vector>

#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "util/errors.h"
#include "util/require_positions.h"
#include "util/require_weight.h"

namespace modal_deform {
namespace {

void require(bool condition, const std::string& what) {
  if (!condition) throw InputError("basis: " + what);
}

// Checked as one contiguous vector: Eigen's allFinite on a row-major matrix (vectors) is many
// times slower than over its storage (docs/measurements.md, "Choices in the core").
template <typename Matrix>
void require_finite(const Matrix& matrix, const char* name) {
  using Vector = Eigen::Matrix<typename Matrix::Scalar, Eigen::Dynamic, 1>;
  require(Eigen::Map<const Vector>(matrix.data(), matrix.size()).allFinite(),
          message(name, " has non-finite entries"));
}

// Runs one of the core's shared input checks on a basis array, its message prefixed like the
// others.
template <typename Check>
void require_shared(Check&& check) {
  try {
    check();
  } catch (const InputError& error) {
    throw InputError(message("basis: ", error.what()));
  }
}

// A stored prolongation: one row per fine vertex, proxy vertices in range (vectors has 3 rows
// per proxy vertex), barycentric weights or zero ones (a vertex held at rest, outside a region).
void require_prolongation(const Prolongation& P, Eigen::Index n, Eigen::Index vector_rows) {
  require(vector_rows > 0 && vector_rows % 3 == 0,
          message("vectors has ", vector_rows, " rows, expected 3 per proxy vertex"));
  const Eigen::Index p = vector_rows / 3;
  require(P.vertices.rows() == n && P.weights.rows() == n,
          message("prolongation has ", P.vertices.rows(), " vertex rows and ", P.weights.rows(),
                  " weight rows for ", n, " vertices"));
  require_finite(P.weights, "prolongation weights");
  constexpr float kSlack = 1e-5f;
  for (Eigen::Index i = 0; i < n; ++i) {
    if ((P.vertices.row(i).array() < 0).any() || (P.vertices.row(i).array() >= p).any())
      require(false, message("prolongation vertices[", i, "] = (", P.vertices.row(i),
                             ") leaves [0, ", p, "), the proxy vertices of vectors"));
    if (!P.weights.row(i).isZero(0) && ((P.weights.row(i).array() < -kSlack).any() ||
                                        std::abs(P.weights.row(i).sum() - 1.0f) > kSlack))
      require(false, message("prolongation weights[", i, "] = (", P.weights.row(i),
                             ") are not barycentric (each in [0, 1], summing to 1) nor all 0"));
  }
}

// A region bake's region: vertices ascending and in range, and every vertex outside held at rest:
// its rows of the basis zero, or on a proxy its prolongation weights.
void require_region(const Basis& b) {
  const Eigen::Index n = b.rest.rows();
  std::vector<char> inside(static_cast<size_t>(n), 0);
  for (Eigen::Index i = 0; i < b.region.size(); ++i) {
    if (b.region[i] < 0 || b.region[i] >= n || (i > 0 && b.region[i] <= b.region[i - 1]))
      require(false, message("region[", i, "] = ", b.region[i], " is not a vertex above region[",
                             i - 1, "] (the region is ascending, in [0, ", n, "))"));
    inside[b.region[i]] = 1;
  }
  for (Eigen::Index v = 0; v < n; ++v) {
    if (inside[v]) continue;
    if (b.on_proxy() && !b.prolongation.weights.row(v).isZero(0))
      require(false, message("prolongation weights[", v, "]: vertex ", v,
                             " lies outside the region but has weights"));
    if (!b.on_proxy() && !b.vectors.middleRows<3>(3 * v).isZero(0))
      require(false,
              message("vectors: vertex ", v, " lies outside the region but has non-zero rows"));
  }
}

}  // namespace

Eigen::Matrix<double, 3, Eigen::Dynamic> Basis::vertex_rows(int v) const {
  if (!on_proxy()) return vectors.middleRows<3>(3 * static_cast<Eigen::Index>(v)).cast<double>();
  Eigen::Matrix<double, 3, Eigen::Dynamic> rows = Eigen::MatrixXd::Zero(3, vectors.cols());
  for (int k = 0; k < 3; ++k)
    rows += static_cast<double>(prolongation.weights(v, k)) *
            vectors.middleRows<3>(3 * static_cast<Eigen::Index>(prolongation.vertices(v, k)))
                .cast<double>();
  return rows;
}

void validate_basis(const Basis& b) {
  const Eigen::Index n = b.rest.rows(), r = b.vectors.cols(), g = b.ghost_vertices.rows();
  require(n > 0, "rest has no vertices");
  require(r > 0, "vectors has no columns");
  require(b.mass.size() == n, message("mass has ", b.mass.size(), " entries for ", n, " vertices"));
  if (b.on_proxy())
    require_prolongation(b.prolongation, n, b.vectors.rows());
  else
    require(b.vectors.rows() == 3 * n,
            message("vectors has ", b.vectors.rows(), " rows, expected ", 3 * n));
  require(0 <= b.num_rigid && b.num_rigid <= b.num_modes && b.num_modes <= r,
          message("num_rigid, num_modes out of order: rigid ", b.num_rigid, ", modes ", b.num_modes,
                  ", dimension ", r));
  require(0 <= b.num_floppy && b.num_floppy <= b.num_modes - b.num_rigid,
          message("num_floppy is ", b.num_floppy, ", outside [0, ", b.num_modes - b.num_rigid,
                  "] (the non-rigid modes)"));
  require(b.eigenvalues.size() == b.num_modes, message("eigenvalues has ", b.eigenvalues.size(),
                                                       " entries for ", b.num_modes, " modes"));
  require(g > 0, "ghost_vertices is empty");
  require(b.ghost_faces.rows() > 0, "ghost_faces is empty");
  require(b.ghost_map.size() == n,
          message("ghost_map has ", b.ghost_map.size(), " entries for ", n, " vertices"));
  require(b.ghost_vectors.rows() == 3 * g && b.ghost_vectors.cols() == r,
          message("ghost_vectors is ", b.ghost_vectors.rows(), " by ", b.ghost_vectors.cols(),
                  ", expected ", 3 * g, " by ", r));
  require(std::isfinite(b.scale) && b.scale > 0,
          message("scale ", b.scale, " is not a positive number"));
  require_shared([&] {
    require_material(b.material, n);
    require_stiffness_paint(ghost_material(b).paint, g, "ghost_stiffness_weights");
  });
  require((b.material.paint.weights.size() == 0) == (b.ghost_stiffness_weights.size() == 0),
          "ghost_stiffness_weights: the ghost is painted when and only when the mesh is");
  require(b.num_dropped >= 0, "num_dropped is negative");
  require_shared([&] { require_vertices(b.rest, "rest"); });
  const double extent = bounding_box_extent(b.rest);
  // The bake's scale is exactly normalizing_scale(rest): anything else was not baked for this mesh.
  require(std::abs(b.scale * extent - kNormalizedExtent) <= 1e-12 * kNormalizedExtent,
          message("scale ", b.scale, " does not scale rest (extent ", extent, ") to ",
                  kNormalizedExtent));
  require_finite(b.mass, "mass");
  require((b.mass.array() >= 0).all(), "mass has negative entries");
  require_finite(b.vectors, "vectors");
  if (b.region.size() > 0) require_region(b);
  require_finite(b.eigenvalues, "eigenvalues");
  require_shared([&] {
    require_positions(flatten(b.ghost_vertices), b.ghost_vertices.size(), "ghost_vertices");
  });
  require_finite(b.ghost_vectors, "ghost_vectors");
  // The messages are formatted only for an offending entry: formatting one per entry would cost
  // far more than the check (docs/measurements.md, "Choices in the core").
  for (Eigen::Index v = 0; v < n; ++v)
    if (b.ghost_map[v] < 0 || b.ghost_map[v] >= g)
      require(false, message("ghost_map[", v, "] = ", b.ghost_map[v], " is outside [0, ", g, ")"));
  for (Eigen::Index f = 0; f < b.ghost_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (b.ghost_faces(f, k) < 0 || b.ghost_faces(f, k) >= g)
        require(false, message("ghost_faces[", f, "] refers to ghost vertex ", b.ghost_faces(f, k),
                               ", outside [0, ", g, ")"));
  // Ghost quantities are weighted means over the fine vertices: positions inside the fine bounding
  // box, each vector entry within the largest of its column in `vectors` (float32 rounding aside).
  const Eigen::RowVector3d low = b.rest.colwise().minCoeff(), high = b.rest.colwise().maxCoeff();
  const double slack = 1e-9 * extent;
  for (Eigen::Index i = 0; i < g; ++i)
    if (!((b.ghost_vertices.row(i).array() >= low.array() - slack) &&
          (b.ghost_vertices.row(i).array() <= high.array() + slack))
             .all())
      require(false, message("ghost_vertices[", i, "] lies outside the bounding box of rest"));
  // The solver evaluates the energy on the ghost in the normalised frame.
  try {
    validate_mesh(b.scale * b.ghost_vertices, b.ghost_faces);
  } catch (const InputError& error) {
    throw InputError(message(
        "basis: ghost_vertices and ghost_faces (scaled) are not a usable mesh: ", error.what()));
  }
  // Row by row, along vectors' storage (a column-wise reduction of the row-major array is slower).
  Eigen::RowVectorXf largest_row = Eigen::RowVectorXf::Zero(r);
  for (Eigen::Index i = 0; i < b.vectors.rows(); ++i)
    largest_row = largest_row.cwiseMax(b.vectors.row(i).cwiseAbs());
  const Eigen::VectorXf largest = largest_row.transpose();
  for (Eigen::Index j = 0; j < r; ++j) {
    Eigen::Index i = 0;
    const double bound =
        1.000001 * static_cast<double>(largest[j]) + std::numeric_limits<float>::min();
    if (b.ghost_vectors.col(j).cwiseAbs().maxCoeff(&i) > bound)
      require(false, message("ghost_vectors[", i, ", ", j, "] = ", b.ghost_vectors(i, j),
                             " exceeds every entry of column ", j,
                             " of vectors; it is not their restriction"));
  }
}

}  // namespace modal_deform
