// Stand-in stiffness matrices for testing the modal linear algebra without the shells energy, and
// the small meshes they are tested on.
//
// spring_network_hessian has the sparsity pattern of the shells Hessian (springs along the edges
// and across the hinges) and the rigid motions of each component in its kernel;
// laplacian_stiffness has the three translations of each component in its kernel.
#pragma once

#include <Eigen/SparseCore>
#include <array>
#include <random>
#include <vector>

#include "mesh/mesh_topology.h"
#include "mesh/primitives.h"
#include "test_support.h"

namespace modal_deform::testing {

// The Hessian at rest of Σ ½ (ℓ − ℓ̄)² / ℓ̄ over springs along the edges and between the two
// opposite vertices of each hinge: 3n by 3n, blocks (1/ℓ̄) u uᵀ for the unit direction u.
inline SparseMatrix spring_network_hessian(const VerticesRef& V, const FacesRef& F) {
  const MeshTopology topology = build_topology(V, F);
  std::vector<std::array<int, 2>> springs = topology.edges;
  for (const Hinge& hinge : topology.hinges)
    springs.push_back({hinge.vertices[2], hinge.vertices[3]});
  std::vector<Eigen::Triplet<double>> triplets;
  for (const auto& [a, b] : springs) {
    const Eigen::Vector3d e = (V.row(a) - V.row(b)).transpose();
    const double length = e.norm();
    if (length == 0) continue;
    const Eigen::Matrix3d block = e * e.transpose() / (length * length * length);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        triplets.emplace_back(3 * a + r, 3 * a + c, block(r, c));
        triplets.emplace_back(3 * b + r, 3 * b + c, block(r, c));
        triplets.emplace_back(3 * a + r, 3 * b + c, -block(r, c));
        triplets.emplace_back(3 * b + r, 3 * a + c, -block(r, c));
      }
  }
  SparseMatrix K(3 * V.rows(), 3 * V.rows());
  K.setFromTriplets(triplets.begin(), triplets.end());
  return K;
}

// The graph Laplacian of the edges (unit weights) ⊗ I₃: 3n by 3n.
inline SparseMatrix laplacian_stiffness(const VerticesRef& V, const FacesRef& F) {
  const MeshTopology topology = build_topology(V, F);
  std::vector<Eigen::Triplet<double>> triplets;
  for (const auto& [a, b] : topology.edges)
    for (int r = 0; r < 3; ++r) {
      triplets.emplace_back(3 * a + r, 3 * a + r, 1.0);
      triplets.emplace_back(3 * b + r, 3 * b + r, 1.0);
      triplets.emplace_back(3 * a + r, 3 * b + r, -1.0);
      triplets.emplace_back(3 * b + r, 3 * a + r, -1.0);
    }
  SparseMatrix K(3 * V.rows(), 3 * V.rows());
  K.setFromTriplets(triplets.begin(), triplets.end());
  return K;
}

// A closed box with its vertices moved at random by up to `jitter`, so that no face is flat and
// the spring network is rigid.
inline TriangleMesh jittered_bar(int nx, int ny, int nz, double jitter, unsigned seed = 7) {
  TriangleMesh mesh = bar(nx, ny, nz, 1.0, 1.0, 2.0);
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-jitter, jitter);
  for (Eigen::Index i = 0; i < mesh.V.size(); ++i) mesh.V.data()[i] += uniform(random);
  return mesh;
}

}  // namespace modal_deform::testing
