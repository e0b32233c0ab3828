#include "solve/pose_objective.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "mesh/mass.h"
#include "mesh/mesh_check.h"
#include "mesh/normalization.h"
#include "util/require_positions.h"

namespace modal_deform {
namespace {

// The side of a triangle from vertex `from` to vertex `to`, in y (3#V): y_to − y_from.
Eigen::Vector3d side(const Eigen::VectorXd& y, int from, int to) {
  return y.segment<3>(3 * static_cast<Eigen::Index>(to)) -
         y.segment<3>(3 * static_cast<Eigen::Index>(from));
}

}  // namespace

PoseObjective::PoseObjective(const VerticesRef& V, const FacesRef& F, const Handles& handles,
                             const Eigen::VectorXd& weights, double stiffness, EnergyKind energy,
                             const Material& material, const std::vector<int>& held)
    : PoseObjective(normalizing_scale(V) * V, normalizing_scale(V), F,
                    Terms{handles, weights, stiffness, energy, material}, held) {}

PoseObjective::PoseObjective(RowMatrixX3d rest, double scale, const FacesRef& F, Terms terms,
                             const std::vector<int>& held)
    : terms_(std::move(terms)),
      transforms_(terms_.handles.size(), Eigen::Matrix4d::Identity()),
      scale_(scale),
      rest_(std::move(rest)),
      energy_(make_energy(terms_.energy, rest_, F, terms_.material)),
      handle_term_(rest_, lumped_mass(rest_, F), terms_.handles, terms_.weights, terms_.stiffness),
      faces_(F) {
  const int n = static_cast<int>(rest_.rows());
  std::vector<Eigen::Index> oriented;
  for (Eigen::Index f = 0; f < faces_.rows(); ++f)
    if (!is_degenerate_face(rest_, faces_, static_cast<int>(f))) oriented.push_back(f);
  oriented_faces_ = faces_(oriented, Eigen::all);
  const Eigen::VectorXd mass = lumped_mass(rest_, F);
  const Eigen::VectorXd handle_diagonal = handle_term_.hessian_diagonal(n);
  const Eigen::VectorXd hessian_diagonal = energy_->hessian(rest_positions()).diagonal();
  mass_diagonal_.resize(3 * n);
  for (int v = 0; v < n; ++v) mass_diagonal_.segment<3>(3 * v).setConstant(mass[v]);
  const double mean_mass = mass_diagonal_.mean();
  mass_diagonal_ = mass_diagonal_.cwiseMax(1e-6 * mean_mass);
  // Coordinates of vertices in no energy term and no handle (no mass, a zero Hessian block) get a
  // fixed diagonal: nothing moves them.
  constant_diagonal_ = handle_diagonal;
  for (int v = 0; v < n; ++v)
    if (mass[v] == 0 && hessian_diagonal.segment<3>(3 * v).isZero(0) &&
        handle_diagonal.segment<3>(3 * v).isZero(0))
      constant_diagonal_.segment<3>(3 * v).setConstant(mean_mass);
  // The floor of the shift: a fraction of the median curvature per unit mass at rest (coordinates
  // in no term left out). The median, not the mean: a raw scan's slivers have terms far stiffer
  // than the rest, which would lift a mean, and τ sitting on a high floor damps every step
  // (bench/results/refine.json, the raw-scan-like dragon).
  std::vector<double> curvature;
  for (Eigen::Index i = 0; i < mass_diagonal_.size(); ++i)
    if (const double c = std::abs(hessian_diagonal[i] + handle_diagonal[i]) / mass_diagonal_[i];
        c > 0)
      curvature.push_back(c);
  const auto middle = curvature.begin() + static_cast<std::ptrdiff_t>(curvature.size() / 2);
  if (!curvature.empty()) std::nth_element(curvature.begin(), middle, curvature.end());
  smallest_shift_ = curvature.empty() ? 0 : 2.5e-8 * *middle;
  // Held coordinates decouple (hessian_into) with a diagonal of their own, so their step is 0.
  if (!held.empty()) held_.assign(3 * static_cast<size_t>(n), 0);
  for (int v : held) {
    std::fill_n(held_.begin() + 3 * static_cast<std::ptrdiff_t>(v), 3, 1);
    constant_diagonal_.segment<3>(3 * v).setConstant(mean_mass);
  }
}

PoseObjective PoseObjective::around(const std::vector<int>& free,
                                    std::vector<int>& vertices) const {
  const int n = static_cast<int>(rest_.rows());
  std::vector<char> is_free(n, 0), near(n, 0);
  for (int v : free) is_free[v] = 1;
  auto touches = [&](const std::vector<char>& marked, Eigen::Index f) {
    return marked[faces_(f, 0)] || marked[faces_(f, 1)] || marked[faces_(f, 2)];
  };
  for (Eigen::Index f = 0; f < faces_.rows(); ++f)
    if (touches(is_free, f)) near[faces_(f, 0)] = near[faces_(f, 1)] = near[faces_(f, 2)] = 1;
  std::vector<Eigen::Index> kept;
  std::vector<int> index(n, -1);  // the parent's vertex → this one's
  for (Eigen::Index f = 0; f < faces_.rows(); ++f)
    if (touches(near, f)) {
      kept.push_back(f);
      for (int k = 0; k < 3; ++k) index[faces_(f, k)] = 0;
    }
  vertices.clear();
  for (int v = 0; v < n; ++v)
    if (index[v] == 0) {
      index[v] = static_cast<int>(vertices.size());
      vertices.push_back(v);
    }
  RowMatrixX3i F(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i)
    for (int k = 0; k < 3; ++k) F(static_cast<Eigen::Index>(i), k) = index[faces_(kept[i], k)];
  RowMatrixX3d rest(static_cast<Eigen::Index>(vertices.size()), 3);
  std::vector<int> held;
  Terms terms = terms_;
  const StiffnessPaint& paint = terms_.material.paint;
  if (!paint.uniform())
    terms.material.paint.weights.resize(static_cast<Eigen::Index>(vertices.size()));
  for (size_t i = 0; i < vertices.size(); ++i) {
    const auto local = static_cast<Eigen::Index>(i);
    rest.row(local) = rest_.row(vertices[i]);
    if (!paint.uniform()) terms.material.paint.weights[local] = paint.weights[vertices[i]];
    if (!is_free[vertices[i]]) held.push_back(static_cast<int>(i));
  }
  for (std::vector<int>& handle : terms.handles) {
    std::vector<int> inside;
    for (int v : handle)
      if (index[v] >= 0) inside.push_back(index[v]);
    handle = std::move(inside);
  }
  PoseObjective local(std::move(rest), 1.0, F, std::move(terms), held);
  local.set_transforms(transforms_);  // already normalised, and the scale is 1
  return local;
}

void PoseObjective::hessian_into(const Eigen::VectorXd& y, bool projected, SparseMatrix& H) const {
  energy_->hessian_into(y, projected, H);
  if (held_.empty()) return;
  for (int col = 0; col < H.outerSize(); ++col)
    for (SparseMatrix::InnerIterator entry(H, col); entry; ++entry)
      if (held_[static_cast<size_t>(entry.row())] || held_[static_cast<size_t>(col)])
        entry.valueRef() = 0;
}

bool PoseObjective::turns_a_triangle_over(const Eigen::VectorXd& y,
                                          const Eigen::VectorXd& y_new) const {
  for (Eigen::Index f = 0; f < oriented_faces_.rows(); ++f) {
    const int a = oriented_faces_(f, 0), b = oriented_faces_(f, 1), c = oriented_faces_(f, 2);
    if (side(y, a, b).cross(side(y, a, c)).dot(side(y_new, a, b).cross(side(y_new, a, c))) < 0)
      return true;
  }
  return false;
}

double PoseObjective::step_to_turning(const Eigen::VectorXd& y, const Eigen::VectorXd& p) const {
  double smallest = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < oriented_faces_.rows(); ++f) {
    const int a = oriented_faces_(f, 0), b = oriented_faces_(f, 1), c = oriented_faces_(f, 2);
    const Eigen::Vector3d e1 = side(y, a, b), e2 = side(y, a, c), d1 = side(p, a, b),
                          d2 = side(p, a, c);
    // n(α) = n + α (e1 × d2 + d1 × e2) + α² d1 × d2, so n·n(α) = c0 + c1 α + c2 α².
    const Eigen::Vector3d n = e1.cross(e2);
    const double c0 = n.squaredNorm(), c1 = n.dot(e1.cross(d2) + d1.cross(e2)),
                 c2 = n.dot(d1.cross(d2));
    if (c0 == 0) continue;  // collapsed already: not counted, as in turns_a_triangle_over
    double root = std::numeric_limits<double>::infinity();
    if (c2 == 0) {
      if (c1 < 0) root = -c0 / c1;
    } else {
      const double discriminant = c1 * c1 - 4 * c2 * c0;
      if (discriminant >= 0) {
        // Both roots by the stable formula; the smaller positive one.
        const double q = -0.5 * (c1 + std::copysign(std::sqrt(discriminant), c1));
        for (const double r : {q / c2, c0 / q})
          if (r > 0) root = std::min(root, r);
      }
    }
    smallest = std::min(smallest, root);
  }
  return smallest;
}

void PoseObjective::set_transforms(Transforms transforms) {
  for (Eigen::Matrix4d& T : transforms) T.topRightCorner<3, 1>() *= scale_;
  handle_term_.set_transforms(transforms);
  transforms_ = std::move(transforms);
}

double PoseObjective::operator()(const Eigen::VectorXd& y, Eigen::VectorXd& gradient) const {
  if (!positions_in_range(y)) return std::numeric_limits<double>::infinity();
  const double value =
      energy_->value_and_gradient(y, gradient) + handle_term_.add_value_and_gradient(y, gradient);
  for (size_t i = 0; i < held_.size(); ++i)
    if (held_[i]) gradient[static_cast<Eigen::Index>(i)] = 0;
  return value;
}

}  // namespace modal_deform
