// Secondary motion on a rig: the inertial forces that a skinned mesh's motion makes its rest-space
// displacement feel, projected on the basis (ReducedDynamics with a rig).
//
// The mesh is skinned by linear blend skinning, y_i = A_i (x̄_i + u_i) with A_i = Σ_b W_ib B_b
// (homogeneous 4 by 4, B_b a bone's world skinning matrix, affine), u = U q the displacement in
// rest space. A point of the rest mesh that the rig carries accelerates in world space by Ä_i x̄_i;
// in the vertex's frame the displacement feels the opposite acceleration pulled back into rest
// space. The pull-back is per bone, c_i = Σ_b W_ib L_b⁻¹ B̈_b x̄_i (L_b the 3 by 3 linear part of
// B_b): each bone's acceleration of the point seen in that bone's frame, blended as skinning blends
// positions. It is exactly L_i⁻¹ Ä_i x̄_i (a free point stays still in world space) where a vertex
// follows one bone or where its bones move together (a rig moving as a whole), and L_bᵀ for rigid
// bones; at a joint bent in between it differs from L_i⁻¹ by the bones' relative turn, and it keeps
// the force linear in the bones' L_b⁻¹ B̈_b, so that the projection on the basis is precomputed per
// bone (L_i⁻¹ of the blended matrix would need every vertex every frame). L_b⁻¹ rather than L_bᵀ:
// with a scaled bone, Lᵀ would scale the felt acceleration by the scale squared, L⁻¹ keeps a point
// free in world space still.
//
// The reduced force per unit of ρ (the reduced mass is ρI, ReducedDynamics) is
//   g = −s⁴ Σ_i m_i U_iᵀ c_i = −s⁴ Σ_b P_b vec(L_b⁻¹ B̈_b),  P_b = Σ_i W_ib m_i U_iᵀ ⊗ (x̄_i, 1)ᵀ,
// with s the normalised frame's scale (the basis is M-orthonormal there: s⁴ Uᵀ M U = I) and P_b
// (r by 12) precomputed once: a frame costs O(b r), whatever the number of vertices.
//
// Not kept, the terms in the displacement itself: the centrifugal and Euler forces L⁻¹ L̈ u and the
// Coriolis force 2 L⁻¹ L̇ u̇. They are first order in the small displacement, the centrifugal one
// relative to the elastic forces as (rig's angular speed / lowest mode's)², and they vanish with
// the rig's motion, as all of the force does; keeping them would cost O(b² r²) a frame (per pair of
// bones sharing vertices) and make the stiffness the artist's period sets depend on the rig's
// speed.
#pragma once

#include <Eigen/Sparse>

#include "basis/basis.h"
#include "solve/handle_term.h"
#include "util/types.h"

namespace modal_deform {

// #V by #bones skinning weights, rows summing to 1.
using SkinningWeights = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// Rows must sum to 1 within this (Blender's Armature modifier normalises them; the add-on passes
// them normalised).
constexpr double kWeightSumTolerance = 1e-4;
// A bone's linear part whose determinant is below this times its largest singular value cubed
// is singular (a bone scaled to zero): its frame has no inverse.
constexpr double kSingularBone = 1e-9;

// Throws InputError for a matrix of the wrong shape, a non-finite or negative weight, or a row not
// summing to 1 (a vertex weighted to no bone is refused: the add-on gives such vertices a bone of
// their own, the object's world matrix, as the Armature modifier leaves them there).
void check_skinning_weights(const SkinningWeights& weights, int num_vertices);

// Skinning weights from compressed-row arrays (row pointers #V + 1, column indices and values
// alike long): the structure is checked before anything indexes by it (InputError naming what is
// wrong), repeated entries of a row are summed; then check_skinning_weights.
SkinningWeights skinning_weights_from_rows(int num_vertices, int num_bones,
                                           const Eigen::VectorXi& row_pointers,
                                           const Eigen::VectorXi& columns,
                                           const Eigen::VectorXd& values);

// Throws InputError unless there is one bone matrix per bone, finite, affine (last row 0 0 0 1),
// with entries at most kMaxCoordinate in magnitude and invertible; the message names the bone.
void check_bone_matrices(const Transforms& bones, int num_bones);

class RigForces {
 public:
  // basis: validated by the caller. weights: check_skinning_weights. Costs O(nonzero weights · r).
  RigForces(const Basis& basis, const SkinningWeights& weights);

  int num_bones() const { return static_cast<int>(projections_.cols() / 12); }

  // g (r) for bones moving from `previous` through `current` to `next` in steps of `dt` seconds
  // (each checked by check_bone_matrices): the acceleration the second difference
  // (next − 2 current + previous)/dt² gives, pulled back by the current bones' linear parts.
  // Exactly zero when the three are equal. Throws InputError naming a bone whose acceleration
  // pulled back, times dt², is beyond kMaxCoordinate (a bone scaled to almost nothing).
  void acceleration(const Transforms& previous, const Transforms& current, const Transforms& next,
                    double dt, Eigen::VectorXd& g) const;

 private:
  double scale4_ = 1;             // s⁴
  Eigen::MatrixXd projections_;   // [P_0 … P_{b−1}], r by 12b, column 12b + 4j + l
  mutable Eigen::VectorXd work_;  // vec(L_b⁻¹ B̈_b) of every bone (12b)
};

}  // namespace modal_deform
