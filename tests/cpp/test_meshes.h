// Meshes the C++ tests share: the scans in ../shared/meshes, read once per process.
#pragma once

#include <map>
#include <string>

#include "mesh/read_mesh.h"

namespace modal_deform::testing {

inline const TriangleMesh& shared_mesh(const std::string& file) {
  static std::map<std::string, TriangleMesh> cache;
  auto it = cache.find(file);
  if (it == cache.end()) it = cache.emplace(file, read_mesh(std::string(MODAL_DEFORM_SHARED_MESHES) + "/" + file)).first;
  return it->second;
}

}  // namespace modal_deform::testing
