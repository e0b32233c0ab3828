// Reading meshes from OBJ and ASCII PLY files, optionally gzip-compressed (tests, benchmarks).
#pragma once

#include <string>

#include "mesh/triangle_mesh.h"

namespace modal_deform {

// Reads `path` (.obj, .ply, either with .gz). Throws InputError naming the file and line on
// anything it cannot read. Polygons are split into fans of triangles.
TriangleMesh read_mesh(const std::string& path);

}  // namespace modal_deform
