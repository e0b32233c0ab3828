// What the C++ tests share: the scans in ../shared/meshes (read once per process), mesh
// helpers, random data, and the check that an input error names its argument.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <string>

#include "mesh/normalization.h"
#include "mesh/read_mesh.h"
#include "util/errors.h"

namespace modal_deform::testing {

inline const TriangleMesh& shared_mesh(const std::string& file) {
  static std::map<std::string, TriangleMesh> cache;
  auto it = cache.find(file);
  if (it == cache.end())
    it = cache.emplace(file, read_mesh(std::string(MODAL_DEFORM_SHARED_MESHES) + "/" + file)).first;
  return it->second;
}

// The mesh scaled to the paper's frame (longest bounding-box edge 10).
inline TriangleMesh normalized(TriangleMesh mesh) {
  mesh.V *= normalizing_scale(mesh.V);
  return mesh;
}

// Meshes a and b as one mesh of two components, b shifted by `offset`.
inline TriangleMesh side_by_side(const TriangleMesh& a, const TriangleMesh& b,
                                 const Eigen::RowVector3d& offset) {
  TriangleMesh both;
  both.V.resize(a.V.rows() + b.V.rows(), 3);
  both.V << a.V, b.V.rowwise() + offset;
  both.F.resize(a.F.rows() + b.F.rows(), 3);
  both.F << a.F, b.F.array() + static_cast<int>(a.V.rows());
  return both;
}

// Entries drawn uniformly from [-1, 1], the same for the same seed.
inline Eigen::VectorXd random_vector(Eigen::Index size, unsigned seed) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd v(size);
  for (Eigen::Index i = 0; i < size; ++i) v[i] = uniform(generator);
  return v;
}

// Expects call() to throw InputError with `needle` in its message.
template <typename Call>
void expect_input_error(Call call, const std::string& needle) {
  try {
    call();
    ADD_FAILURE() << "no InputError, expected one naming " << needle;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(needle), std::string::npos) << error.what();
  }
}

}  // namespace modal_deform::testing
