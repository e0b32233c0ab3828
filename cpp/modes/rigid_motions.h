// The rigid motions of each connected component: the kernel of a rigid-invariant energy's Hessian
// at rest.
#pragma once

#include "util/types.h"

namespace modal_deform {

// The rigid motions of a component: its translations, then its rotations.
constexpr int kTranslations = 3;
constexpr int kRotations = 3;
constexpr int kRigidMotions = kTranslations + kRotations;

// For each component k of (V, component): its 3 translations and its 3 rotations linearised about
// its mass-weighted centroid (the rotations about its principal axes of inertia), M-orthonormal.
// V: #V by 3; component: #V labels in [-1, c), -1 for a vertex outside every component, whose
// rows are zero; mass: #V lumped vertex masses, M = diag(mass) ⊗ I₃.
// Returns 3#V by 6c, columns 6k .. 6k + 5 for component k: translations along x, y, z, then the
// rotations in ascending order of their moment of inertia. Throws InputError for a label outside
// [-1, c), a component without vertices or without mass, or one whose massive vertices lie on a
// line (it has no third rotation).
Eigen::MatrixXd rigid_motions(const VerticesRef& V,
                              const Eigen::Ref<const Eigen::VectorXi>& component,
                              const VectorRef& mass);

}  // namespace modal_deform
