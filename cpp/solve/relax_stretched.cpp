#include "solve/relax_stretched.h"

#include <vector>

namespace modal_deform {
namespace {

// The local solve is small (tens of vertices free, a few hundred around them): it goes to the
// full solve's tolerance, since a looser one costs the full solve more factorisations
// (docs/measurements.md, "Choices in the core").
constexpr double kRelaxTolerance = 1e-8;
constexpr int kRelaxIterations = 100;

// The vertices (not held) of the edges y stretches beyond kStretchedBeyond times their rest
// length (edges of length 0 at rest left out), ascending.
std::vector<int> stretched_vertices(const PoseObjective& objective, const Eigen::VectorXd& y) {
  const RowMatrixX3d& rest = objective.rest();
  const RowMatrixX3i& F = objective.faces();
  std::vector<char> stretched(static_cast<size_t>(rest.rows()), 0);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      const double rest_length = (rest.row(a) - rest.row(b)).norm();
      // A zero-length rest edge (a raw scan's unwelded duplicate) has no term to stretch.
      if (rest_length > 0 &&
          (y.segment<3>(3 * a) - y.segment<3>(3 * b)).norm() > kStretchedBeyond * rest_length)
        stretched[a] = stretched[b] = 1;
    }
  std::vector<int> vertices;
  for (int v = 0; v < static_cast<int>(stretched.size()); ++v)
    if (stretched[v] && !objective.held(v)) vertices.push_back(v);
  return vertices;
}

}  // namespace

int relax_stretched(const PoseObjective& objective, NewtonPoint& point) {
  const std::vector<int> free = stretched_vertices(objective, point.y);
  if (free.empty()) return 0;
  std::vector<int> vertices;
  const PoseObjective local = objective.around(free, vertices);
  // Coordinates of the local objective's vertex i: the parent's vertex vertices[i].
  auto at = [&](Eigen::VectorXd& y, size_t i) {
    return y.segment<3>(3 * static_cast<Eigen::Index>(i));
  };
  const auto size = static_cast<Eigen::Index>(3 * vertices.size());
  NewtonPoint near{Eigen::VectorXd(size), 0, Eigen::VectorXd(size)};
  for (size_t i = 0; i < vertices.size(); ++i) at(near.y, i) = at(point.y, vertices[i]);
  near.value = local(near.y, near.gradient);
  // exact_below = target: the projected Hessian throughout, the robust one far from the minimum.
  const double target = kRelaxTolerance * near.gradient.norm();
  ShiftedNewton(local).minimize(near, target, kRelaxIterations, target, [](const NewtonPoint&) {});
  for (size_t i = 0; i < vertices.size(); ++i) at(point.y, vertices[i]) = at(near.y, i);
  point.value = objective(point.y, point.gradient);
  return static_cast<int>(free.size());
}

}  // namespace modal_deform
