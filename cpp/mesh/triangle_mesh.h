// A triangle mesh as two arrays, the form in which meshes enter and leave the core.
#pragma once

#include <vector>

#include "util/types.h"

namespace modal_deform {

struct TriangleMesh {
  RowMatrixX3d V;  // #V by 3 positions
  RowMatrixX3i F;  // #F by 3 vertex indices
};

// The mesh of flat buffers: positions (x0 y0 z0 x1 ...) and triangle indices (a0 b0 c0 a1 ...).
inline TriangleMesh mesh_from_buffers(const std::vector<double>& positions,
                                      const std::vector<int>& faces) {
  TriangleMesh mesh;
  mesh.V = Eigen::Map<const RowMatrixX3d>(positions.data(),
                                          static_cast<Eigen::Index>(positions.size() / 3), 3);
  mesh.F =
      Eigen::Map<const RowMatrixX3i>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);
  return mesh;
}

}  // namespace modal_deform
