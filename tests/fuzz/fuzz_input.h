// Structured fuzz input: bytes to counts, awkward numbers, meshes, options, handles and
// transforms, so that a short byte string reaches every awkward case of the corpus (empty and
// lone-vertex meshes, duplicate and unreferenced vertices, zero-area and needle faces, repeated
// and out-of-range indices, flipped and duplicated faces, debris components, NaN, infinities,
// extreme scales, non-rigid transforms).
//
// Reading past the end gives zeros, so every byte string decodes to something. Each read is a
// statement of its own: the order in which a call's arguments are evaluated differs between
// compilers (clang: left to right, gcc: right to left), and the C++ suite (gcc) must decode the
// fuzzers' (clang) inputs as they did. (Where an assignment once read both sides, the right side,
// which C++17 evaluates first, still reads first.)
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "mesh/primitives.h"
#include "mesh/triangle_mesh.h"
#include "solve/handle_term.h"

namespace modal_deform::fuzz {

// Numbers that break naive geometry code.
inline double awkward_number(std::uint8_t choice) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double numbers[] = {0.0,
                            -0.0,
                            1.0,
                            -1.0,
                            0.5,
                            1e-6,
                            1e6,
                            1e-30,
                            1e30,
                            1e-300,
                            1e300,
                            5e-324,
                            1.7e308,
                            -1.7e308,
                            kInf,
                            -kInf,
                            std::numeric_limits<double>::quiet_NaN(),
                            1 + 1e-15,
                            3.0,
                            1e15};
  return numbers[choice % (sizeof numbers / sizeof numbers[0])];
}

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  bool flag() { return byte() & 1; }
  // An integer in [low, high] (high − low < 65536).
  int integer(int low, int high) {
    const unsigned span = static_cast<unsigned>(high - low) + 1;
    unsigned raw = byte();
    if (span > 256) raw = raw << 8 | byte();
    return low + static_cast<int>(raw % span);
  }
  // Any double, NaN and infinities included, from 8 raw bytes.
  double raw_double() {
    std::uint64_t bits = 0;
    for (int k = 0; k < 8; ++k) bits = bits << 8 | byte();
    double value;
    std::memcpy(&value, &bits, sizeof value);
    return value;
  }
  // Mostly ordinary values in [−2, 2] in steps of 1/64; sometimes awkward ones.
  double number() {
    const std::uint8_t kind = byte();
    if (kind < 200) return (static_cast<int>(byte()) - 128) / 64.0;
    if (kind < 250) return awkward_number(byte());
    return raw_double();
  }
  // A weight or stiffness: mostly positive and sensible, sometimes awkward.
  double positive() {
    const std::uint8_t kind = byte();
    if (kind < 220) return 0.25 + kind / 32.0;
    return awkward_number(byte());
  }
  bool exhausted() const { return at_ >= size_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

// A vertex index: mostly in [0, n), sometimes −1 or past the end.
inline int vertex_index(FuzzInput& in, int n) {
  const std::uint8_t b = in.byte();
  if (b == 255) return -1 - in.byte();
  if (b == 254 || n == 0) return n + in.byte();
  return b % n;
}

// A mesh either from a generated shape changed by a list of edits, or made from scratch.
// At most about max_vertices vertices and max_faces faces.
inline TriangleMesh fuzz_mesh(FuzzInput& in, int max_vertices, int max_faces) {
  TriangleMesh mesh;
  const std::uint8_t kind = in.byte() % 8;
  if (kind < 5) {
    switch (kind) {
      case 0: {
        const int nx = in.integer(1, 3), ny = in.integer(1, 3);
        mesh = grid(nx, ny, 1.0, in.number());
        break;
      }
      case 1: {
        const int around = in.integer(3, 5), along = in.integer(1, 2);
        mesh = cylinder(around, along, 0.5, 2.0);
        break;
      }
      case 2:
        mesh = bar(1, 1, in.integer(1, 2), 1.0, 1.0, 2.0);
        break;
      case 3: {
        const int cells = in.integer(1, 3), bumps = in.integer(0, 2);
        const double height = in.number();
        mesh = bumpy_plane(cells, 2.0, bumps, height, in.byte());
        break;
      }
      default:
        mesh = mesh_from_buffers({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2});
        break;
    }
  } else {
    const int n = in.integer(0, max_vertices), m = in.integer(0, max_faces);
    std::vector<double> positions;
    for (int v = 0; v < n; ++v) {
      const std::uint8_t how = in.byte() % 8;
      if (how < 5 ||
          v == 0) {  // on a small lattice: collinear, coplanar and coincident points abound
        for (int c = 0; c < 3; ++c) positions.push_back(in.integer(-2, 2) * 0.5);
      } else if (how ==
                 5) {  // a copy of an earlier vertex, maybe nudged: zero-area and needle faces
        const int of = in.integer(0, v - 1);
        const double nudge = in.flag() ? 1e-9 : 0.0;
        for (int c = 0; c < 3; ++c)
          positions.push_back(positions[3 * of + c] + (c == 0 ? nudge : 0.0));
      } else {
        for (int c = 0; c < 3; ++c) positions.push_back(in.number());
      }
    }
    std::vector<int> faces;
    for (int f = 0; f < 3 * m; ++f) faces.push_back(vertex_index(in, n));
    mesh = mesh_from_buffers(positions, faces);
  }

  const int edits = in.integer(0, 6);
  for (int e = 0; e < edits; ++e) {
    const auto n = static_cast<int>(mesh.V.rows()), m = static_cast<int>(mesh.F.rows());
    switch (in.byte() % 10) {
      case 0:  // an awkward coordinate
        if (n) {
          const double value = in.number();
          const int v = in.integer(0, n - 1), c = in.integer(0, 2);
          mesh.V(v, c) = value;
        }
        break;
      case 1:  // a vertex moved onto another
        if (n) {
          const int from = in.integer(0, n - 1), to = in.integer(0, n - 1);
          mesh.V.row(to) = mesh.V.row(from).eval();
        }
        break;
      case 2:  // a flipped face
        if (m) {
          const int f = in.integer(0, m - 1);
          std::swap(mesh.F(f, 1), mesh.F(f, 2));
        }
        break;
      case 3:  // a face repeated, maybe flipped: duplicate faces, double sheets, non-manifold edges
        if (m && m < max_faces) {
          const Eigen::RowVector3i face = mesh.F.row(in.integer(0, m - 1));
          mesh.F.conservativeResize(m + 1, 3);
          mesh.F.row(m) = in.flag() ? face : Eigen::RowVector3i(face[0], face[2], face[1]);
        }
        break;
      case 4:  // a face on any three indices, in range or not
        if (m < max_faces) {
          mesh.F.conservativeResize(m + 1, 3);
          for (int k = 0; k < 3; ++k) mesh.F(m, k) = vertex_index(in, n);
        }
        break;
      case 5:  // an unreferenced vertex
        if (n < max_vertices) {
          mesh.V.conservativeResize(n + 1, 3);
          for (int c = 0; c < 3; ++c) mesh.V(n, c) = in.number();
        }
        break;
      case 6:  // a shrunken copy beside it: debris, another component
        if (2 * n <= max_vertices && 2 * m <= max_faces) {
          const double shrink = in.flag() ? 0.01 : 1.0;
          const Eigen::RowVector3d offset(in.number(), 3.0, 0.0);
          mesh.V.conservativeResize(2 * n, 3);
          mesh.V.bottomRows(n) = (shrink * mesh.V.topRows(n)).rowwise() + offset;
          mesh.F.conservativeResize(2 * m, 3);
          mesh.F.bottomRows(m) = mesh.F.topRows(m).array() + n;
        }
        break;
      case 7:  // a face with a repeated index
        if (m) {
          const int f = in.integer(0, m - 1);
          mesh.F(f, 2) = mesh.F(f, in.integer(0, 1));
        }
        break;
      case 8:  // everything scaled: tiny and huge meshes
        mesh.V *= awkward_number(in.byte());
        break;
      default:  // a face removed
        if (m) {
          const int f = in.integer(0, m - 1);
          mesh.F.row(f) = mesh.F.row(m - 1).eval();
          mesh.F.conservativeResize(m - 1, 3);
        }
        break;
    }
  }
  return mesh;
}

// Up to max_handles handles of up to max_size vertex indices (in range or not, repeats possible).
inline Handles fuzz_handles(FuzzInput& in, int num_vertices, int max_handles, int max_size) {
  Handles handles(in.integer(0, max_handles));
  for (auto& handle : handles) {
    const std::uint8_t how = in.byte() % 8;
    if (how == 0) {  // every vertex
      for (int v = 0; v < num_vertices; ++v) handle.push_back(v);
    } else {
      handle.resize(in.integer(how == 1 ? 0 : 1, max_size));
      for (int& v : handle) v = vertex_index(in, num_vertices);
    }
  }
  return handles;
}

// One transform per handle: mostly rigid (a rotation about a random axis and a translation),
// sometimes scaled, sheared, mirrored or not finite.
inline Transforms fuzz_transforms(FuzzInput& in, int count) {
  Transforms transforms;
  for (int h = 0; h < count; ++h) {
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    Eigen::Vector3d axis;
    for (int c = 0; c < 3; ++c) axis[c] = in.number();
    axis[2] += 0.01;
    if (!(axis.norm() > 0) || !axis.allFinite()) axis = Eigen::Vector3d::UnitZ();
    T.topLeftCorner<3, 3>() =
        Eigen::AngleAxisd(in.integer(-12, 12) * 0.5, axis.normalized()).toRotationMatrix();
    for (int c = 0; c < 3; ++c) T(c, 3) = in.number();
    if (in.byte() > 240) {
      const double value = in.number();
      const int row = in.integer(0, 3), column = in.integer(0, 3);
      T(row, column) = value;
    }
    transforms.push_back(T);
  }
  return transforms;
}

}  // namespace modal_deform::fuzz
