#include "reduction/prolongation.h"

#include <limits>
#include <vector>

#include "linalg/row_blocks.h"
#include "mesh/closest_point.h"
#include "util/errors.h"

namespace modal_deform {

Prolongation prolongation_to_proxy(const VerticesRef& V, const VerticesRef& proxy_V,
                                   const FacesRef& proxy_F,
                                   const Eigen::Ref<const Eigen::VectorXi>& cluster) {
  const Eigen::Index n = V.rows(), p = proxy_V.rows();
  if (cluster.size() != n)
    throw InputError(
        message("cluster: expected ", n, " entries (one per fine vertex), got ", cluster.size()));
  for (Eigen::Index i = 0; i < n; ++i)
    if (cluster[i] < 0 || cluster[i] >= p)
      throw InputError(message("cluster[", i, "] = ", cluster[i], " is outside [0, ", p, ")"));
  // The triangles around each proxy vertex, compressed by vertex.
  std::vector<int> first(static_cast<size_t>(p) + 1, 0);
  for (Eigen::Index f = 0; f < proxy_F.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++first[static_cast<size_t>(proxy_F(f, k)) + 1];
  for (Eigen::Index x = 0; x < p; ++x) first[x + 1] += first[x];
  std::vector<int> faces(static_cast<size_t>(first[p])), next(first.begin(), first.end() - 1);
  for (Eigen::Index f = 0; f < proxy_F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      faces[static_cast<size_t>(next[proxy_F(f, k)]++)] = static_cast<int>(f);

  Prolongation prolongation;
  prolongation.vertices.resize(n, 3);
  prolongation.weights.resize(n, 3);
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < n; ++i) {
    const int c = cluster[i];
    const Eigen::Vector3d x = V.row(i).transpose();
    double nearest = std::numeric_limits<double>::infinity();
    prolongation.vertices.row(i) << c, c, c;
    prolongation.weights.row(i) << 1, 0, 0;
    for (int j = first[c]; j < first[c + 1]; ++j) {
      const int f = faces[static_cast<size_t>(j)];
      const Eigen::Vector3d a = proxy_V.row(proxy_F(f, 0)), b = proxy_V.row(proxy_F(f, 1)),
                            d = proxy_V.row(proxy_F(f, 2));
      const Eigen::Vector3d w = closest_point_barycentric(x, a, b, d);
      const double distance = (w[0] * a + w[1] * b + w[2] * d - x).squaredNorm();
      if (distance < nearest) {
        nearest = distance;
        prolongation.vertices.row(i) = proxy_F.row(f);
        prolongation.weights.row(i) = w.cast<float>().transpose();
      }
    }
  }
  return prolongation;
}

Prolongation held_at_rest(Eigen::Index num_vertices) {
  return {RowMatrixX3i::Zero(num_vertices, 3), RowMatrixX3f::Zero(num_vertices, 3)};
}

void prolongate_positions(const Prolongation& prolongation, const float* rest,
                          const float* proxy_displacement, float* out) {
  const int* vertices = prolongation.vertices.data();
  const float* weights = prolongation.weights.data();
  for_row_blocks(prolongation.size(), [&](Eigen::Index first, Eigen::Index count) {
    for (Eigen::Index i = first; i < first + count; ++i) {
      const float* d0 = proxy_displacement + 3 * vertices[3 * i];
      const float* d1 = proxy_displacement + 3 * vertices[3 * i + 1];
      const float* d2 = proxy_displacement + 3 * vertices[3 * i + 2];
      const float w0 = weights[3 * i], w1 = weights[3 * i + 1], w2 = weights[3 * i + 2];
      for (int a = 0; a < 3; ++a) {
        const float d = w0 * d0[a] + w1 * d1[a] + w2 * d2[a];
        out[3 * i + a] = rest ? rest[3 * i + a] + d : d;
      }
    }
  });
}

}  // namespace modal_deform
