#include "mesh/edge_collapse.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <queue>
#include <tuple>
#include <vector>

#include "mesh/mesh_check.h"
#include "util/bake_stages.h"
#include "util/errors.h"
#include "util/math_constants.h"

namespace modal_deform {
namespace {

// Weight of a boundary edge's constraint plane (through the edge, perpendicular to its face),
// per edge length squared; face planes weigh their area.
constexpr double kBoundaryWeight = 10.0;
// Weight of Ward's criterion (how much the cluster's second moment about its centroid grows)
// added to the quadric error. Both are area times length squared; where the quadric is flat
// this keeps clusters compact and alike in size instead of growing one cluster at random.
constexpr double kCompactnessWeight = 0.1;
// Two faces that a collapse lays on each other cancel when their four vertices are this close to
// one plane (is_double_sheet: the volume they span over the cube of their longest distance).
constexpr double kSheetThickness = 1e-2;
// Collapses go in rounds (collapse_in_rounds) down to this many times the target.
constexpr int kRoundsAbove = 2;
// Heap pops between progress reports (a pop takes microseconds).
constexpr long kReportInterval = 256;

// Sum of weighted squared distances to planes: q(p) = pᵀAp + 2bᵀp + c with A symmetric,
// stored as A00 A01 A02 A11 A12 A22 b0 b1 b2 c.
class Quadric {
 public:
  Quadric() { c_.fill(0.0); }

  // w (n·p + d)² for the plane n·p + d = 0, n of unit length.
  static Quadric plane(const Eigen::Vector3d& n, double d, double w) {
    Quadric q;
    q.c_ = {w * n.x() * n.x(), w * n.x() * n.y(), w * n.x() * n.z(), w * n.y() * n.y(),
            w * n.y() * n.z(), w * n.z() * n.z(), w * d * n.x(),     w * d * n.y(),
            w * d * n.z(),     w * d * d};
    return q;
  }

  Quadric& operator+=(const Quadric& other) {
    for (int i = 0; i < 10; ++i) c_[i] += other.c_[i];
    return *this;
  }

  double operator()(const Eigen::Vector3d& p) const {
    const double x = p.x(), y = p.y(), z = p.z();
    return x * (c_[0] * x + 2 * (c_[1] * y + c_[2] * z + c_[6])) +
           y * (c_[3] * y + 2 * (c_[4] * z + c_[7])) + z * (c_[5] * z + 2 * c_[8]) + c_[9];
  }

 private:
  std::array<double, 10> c_;
};

// The fine vertices merged into one vertex, summarised by what the collapse needs.
struct Cluster {
  Quadric quadric;
  Eigen::Vector3d weighted_sum = Eigen::Vector3d::Zero();  // Σ m_i x_i
  Eigen::Vector3d plain_sum = Eigen::Vector3d::Zero();     // Σ x_i
  double mass = 0;
  int count = 0;
};

// Mass-weighted centroid of the union of a and b; the plain mean when it has no mass.
Eigen::Vector3d merged_centroid(const Cluster& a, const Cluster& b) {
  const double mass = a.mass + b.mass;
  if (mass > 0) return (a.weighted_sum + b.weighted_sum) / mass;
  return (a.plain_sum + b.plain_sum) / (a.count + b.count);
}

struct TriangleShape {
  Eigen::Vector3d normal;  // (b - a) × (c - a), of length twice the area
  double quality;          // 4√3·area / Σ edge², 1 for an equilateral triangle
  bool degenerate;         // the test of is_degenerate_face
};

TriangleShape triangle_shape(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  TriangleShape shape;
  shape.normal = (b - a).cross(c - a);
  const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  const double twice_area = shape.normal.norm();
  shape.quality = ab + bc + ca > 0 ? 2 * std::sqrt(3.0) * twice_area / (ab + bc + ca) : 0.0;
  shape.degenerate = twice_area <= kDegenerateAreaRatio * std::max({ab, bc, ca});
  return shape;
}

struct Neighbour {
  int vertex;
  int faces;  // faces containing both this vertex and the centre
  int face;   // one of them
};

struct Candidate {
  double cost;  // negative for the edge of a degenerate face, which goes first
  int u, v;
  int version_u, version_v;
  bool operator>(const Candidate& other) const { return cost > other.cost; }
};

class Simplifier {
 public:
  Simplifier(const VerticesRef& V, const FacesRef& F, const VectorRef& mass,
             std::vector<char> sides);
  void simplify(int target, Progress* progress);
  EdgeCollapse result();

 private:
  bool has_vertex(int f, int x) const {
    return faces_(f, 0) == x || faces_(f, 1) == x || faces_(f, 2) == x;
  }
  bool same_side(int x, int y) const { return sides_.empty() || sides_[x] == sides_[y]; }
  bool keeps_the_sides(int u, int v) const;
  bool find_cancelled_faces(int u, int v);
  bool is_double_sheet(int u, int v, int p, int q) const;
  bool is_cancelled(int f) const {
    return std::find(cancelled_.begin(), cancelled_.end(), f) != cancelled_.end();
  }
  const std::vector<int>& live_faces(int x);
  void tally_neighbours(int x, std::vector<Neighbour>& out);
  void add_boundary_quadrics();
  void seed();
  void add_candidates(int x, bool higher_only, std::vector<Candidate>& out);
  void push_edges(int x, bool higher_only);
  void collapse_in_rounds(int until, const std::function<void()>& report);
  double cost(int u, int v) const;
  int try_collapse(int u, int v);
  bool face_stays_sound(int f, int u, int v, const Eigen::Vector3d& p) const;
  double star_quality(int u, int v, const Eigen::Vector3d& p, bool merged) const;
  void collapse(int u, int v, const Eigen::Vector3d& p);

  RowMatrixX3i faces_;  // the kept input faces; a collapse of v into u renames v to u
  std::vector<char> face_alive_;
  std::vector<Eigen::Vector3d>
      input_normals_;  // unit normal of each kept input face, 0 if degenerate
  std::vector<std::vector<int>>
      vertex_faces_;  // faces around each vertex; dead ones dropped lazily
  std::vector<Cluster> clusters_;
  std::vector<Eigen::Vector3d> position_;  // centroid of each live cluster
  std::vector<int> version_;               // bumped whenever a vertex's cluster grows
  std::vector<int> merged_into_;           // -1 for a live vertex or one no face uses
  std::vector<char> alive_;
  std::vector<char> sides_;  // empty: one side
  int num_alive_ = 0;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
  // Scratch space of try_collapse and push_edges, kept to avoid allocations per collapse.
  std::vector<int> shared_, u_only_, v_only_, cancelled_, degenerate_faces_;
  std::vector<Neighbour> around_u_, around_v_;
  std::vector<Candidate> candidates_;
};

Simplifier::Simplifier(const VerticesRef& V, const FacesRef& F, const VectorRef& mass,
                       std::vector<char> sides)
    : sides_(std::move(sides)) {
  const int n = static_cast<int>(V.rows());
  // Faces on the same three vertices: oppositely oriented copies cancel in pairs (together they
  // are a sheet of no thickness, which decimated scans are full of); one copy of the orientation
  // left over, if any, stays. Faces with repeated indices go.
  struct Copy {
    std::array<int, 3> key;  // the vertices in increasing order
    int orientation;         // +1 when the face runs through key cyclically, -1 otherwise
    int face;
    bool operator<(const Copy& other) const {
      return std::tie(key, face) < std::tie(other.key, other.face);
    }
  };
  std::vector<Copy> copies;
  copies.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || c == a) continue;
    std::array<int, 3> key{a, b, c};
    std::sort(key.begin(), key.end());
    copies.push_back({key, (a < b) + (b < c) + (c < a) == 2 ? 1 : -1, f});
  }
  std::sort(copies.begin(), copies.end());
  std::vector<int> kept;
  for (size_t begin = 0, end; begin < copies.size(); begin = end) {
    int net = 0;
    for (end = begin; end < copies.size() && copies[end].key == copies[begin].key; ++end)
      net += copies[end].orientation;
    for (size_t i = begin; i < end && net != 0; ++i)
      if (copies[i].orientation * net > 0) {
        kept.push_back(copies[i].face);
        break;
      }
  }
  std::sort(kept.begin(), kept.end());

  const int num_faces = static_cast<int>(kept.size());
  if (num_faces == 0)
    throw InputError(
        "F: no triangle is left once faces with repeated vertices and oppositely oriented copies "
        "go");
  faces_.resize(num_faces, 3);
  for (int f = 0; f < num_faces; ++f) faces_.row(f) = F.row(kept[f]);
  face_alive_.assign(num_faces, 1);

  std::vector<int> degree(n, 0);
  for (int f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k) ++degree[faces_(f, k)];
  vertex_faces_.resize(n);
  for (int x = 0; x < n; ++x) vertex_faces_[x].reserve(degree[x]);
  for (int f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k) vertex_faces_[faces_(f, k)].push_back(f);

  clusters_.resize(n);
  position_.resize(n);
  for (int x = 0; x < n; ++x) {
    position_[x] = V.row(x).transpose();
    clusters_[x].weighted_sum = mass[x] * position_[x];
    clusters_[x].plain_sum = position_[x];
    clusters_[x].mass = mass[x];
    clusters_[x].count = 1;
  }
  input_normals_.resize(num_faces);
  for (int f = 0; f < num_faces; ++f) {
    const Eigen::Vector3d& a = position_[faces_(f, 0)];
    const TriangleShape shape = triangle_shape(a, position_[faces_(f, 1)], position_[faces_(f, 2)]);
    input_normals_[f] = shape.degenerate ? Eigen::Vector3d::Zero() : shape.normal.normalized();
    if (shape.degenerate) continue;
    const Quadric plane =
        Quadric::plane(input_normals_[f], -input_normals_[f].dot(a), 0.5 * shape.normal.norm());
    for (int k = 0; k < 3; ++k) clusters_[faces_(f, k)].quadric += plane;
  }
  add_boundary_quadrics();

  version_.assign(n, 0);
  merged_into_.assign(n, -1);
  alive_.assign(n, 0);
  for (int x = 0; x < n; ++x) alive_[x] = !vertex_faces_[x].empty();
  num_alive_ = static_cast<int>(std::count(alive_.begin(), alive_.end(), 1));
}

const std::vector<int>& Simplifier::live_faces(int x) {
  auto& faces = vertex_faces_[x];
  faces.erase(std::remove_if(faces.begin(), faces.end(), [this](int f) { return !face_alive_[f]; }),
              faces.end());
  return faces;
}

void Simplifier::tally_neighbours(int x, std::vector<Neighbour>& out) {
  out.clear();
  for (int f : live_faces(x))
    for (int k = 0; k < 3; ++k) {
      const int w = faces_(f, k);
      if (w == x) continue;
      auto it =
          std::find_if(out.begin(), out.end(), [w](const Neighbour& s) { return s.vertex == w; });
      if (it == out.end())
        out.push_back({w, 1, f});
      else
        ++it->faces;
    }
}

// Garland–Heckbert's boundary constraint: a plane through each boundary edge, perpendicular to
// its face, so merging along a curved or cornered boundary costs what it cuts off.
void Simplifier::add_boundary_quadrics() {
  for (int x = 0; x < static_cast<int>(vertex_faces_.size()); ++x) {
    tally_neighbours(x, around_u_);
    for (const Neighbour& s : around_u_) {
      if (s.faces != 1 || s.vertex < x || input_normals_[s.face].squaredNorm() == 0) continue;
      const Eigen::Vector3d edge = position_[s.vertex] - position_[x];
      const Eigen::Vector3d normal = edge.cross(input_normals_[s.face]).normalized();
      const Quadric plane =
          Quadric::plane(normal, -normal.dot(position_[x]), kBoundaryWeight * edge.squaredNorm());
      clusters_[x].quadric += plane;
      clusters_[s.vertex].quadric += plane;
    }
  }
}

double Simplifier::cost(int u, int v) const {
  const Cluster &a = clusters_[u], &b = clusters_[v];
  const Eigen::Vector3d p = merged_centroid(a, b);
  const double quadric_error = std::max(0.0, a.quadric(p) + b.quadric(p));
  const double mass = a.mass + b.mass;
  const double ward =
      mass > 0 ? a.mass * b.mass / mass * (position_[u] - position_[v]).squaredNorm() : 0.0;
  return quadric_error + kCompactnessWeight * ward;
}

void Simplifier::add_candidates(int x, bool higher_only, std::vector<Candidate>& out) {
  tally_neighbours(x, around_u_);
  degenerate_faces_.clear();
  for (int f : vertex_faces_[x])
    if (triangle_shape(position_[faces_(f, 0)], position_[faces_(f, 1)], position_[faces_(f, 2)])
            .degenerate)
      degenerate_faces_.push_back(f);
  for (const Neighbour& s : around_u_) {
    if ((higher_only && s.vertex < x) || !same_side(x, s.vertex)) continue;
    const bool on_degenerate_face = std::any_of(degenerate_faces_.begin(), degenerate_faces_.end(),
                                                [&](int f) { return has_vertex(f, s.vertex); });
    out.push_back({on_degenerate_face ? -1.0 : cost(x, s.vertex), x, s.vertex, version_[x],
                   version_[s.vertex]});
  }
}

void Simplifier::push_edges(int x, bool higher_only) {
  candidates_.clear();
  add_candidates(x, higher_only, candidates_);
  for (const Candidate& c : candidates_) heap_.push(c);
}

void Simplifier::seed() {
  for (int x = 0; x < static_cast<int>(alive_.size()); ++x)
    if (alive_[x]) push_edges(x, true);
}

bool Simplifier::face_stays_sound(int f, int u, int v, const Eigen::Vector3d& p) const {
  std::array<Eigen::Vector3d, 3> before, after;
  for (int k = 0; k < 3; ++k) {
    const int x = faces_(f, k);
    before[k] = position_[x];
    after[k] = (x == u || x == v) ? p : position_[x];
  }
  const TriangleShape old_shape = triangle_shape(before[0], before[1], before[2]);
  const TriangleShape new_shape = triangle_shape(after[0], after[1], after[2]);
  if (new_shape.degenerate) return old_shape.degenerate;
  const double max_turn_cosine = std::cos(kMaxNormalTurnDegrees * kPi / 180.0);
  // A needle's normal turns with any small move of its vertices: only sound faces must not turn.
  if (!old_shape.degenerate && old_shape.quality >= kMinFaceQuality &&
      new_shape.normal.dot(old_shape.normal) <
          max_turn_cosine * new_shape.normal.norm() * old_shape.normal.norm())
    return false;
  // Turning in small steps must not add up to a flip against the input.
  return new_shape.normal.dot(input_normals_[f]) > 0 || input_normals_[f].squaredNorm() == 0;
}

// The least quality of the faces around u and v (shared_, u_only_, v_only_) as they are, or of
// those around the merged vertex at p once v is merged into u (`merged`).
double Simplifier::star_quality(int u, int v, const Eigen::Vector3d& p, bool merged) const {
  const auto point = [&](int x) -> const Eigen::Vector3d& {
    return merged && (x == u || x == v) ? p : position_[x];
  };
  const auto quality = [&](int f) {
    return triangle_shape(point(faces_(f, 0)), point(faces_(f, 1)), point(faces_(f, 2))).quality;
  };
  double least = 1.0;
  for (const std::vector<int>* faces : {&u_only_, &v_only_, &shared_}) {
    if (merged && faces == &shared_) continue;
    for (int f : *faces)
      if (!merged || !is_cancelled(f)) least = std::min(least, quality(f));
  }
  return least;
}

// Collapses the edge uv if that keeps the mesh sound; returns the vertex that stays, or -1.
int Simplifier::try_collapse(int u, int v) {
  if (live_faces(u).size() < live_faces(v).size()) std::swap(u, v);  // rename the smaller star
  shared_.clear();
  u_only_.clear();
  v_only_.clear();
  for (int f : vertex_faces_[u]) (has_vertex(f, v) ? shared_ : u_only_).push_back(f);
  for (int f : vertex_faces_[v])
    if (!has_vertex(f, u)) v_only_.push_back(f);
  if (shared_.empty() || (u_only_.empty() && v_only_.empty())) return -1;

  // Boundary: merge two boundary vertices only along a boundary edge, never a boundary vertex
  // with an interior one.
  tally_neighbours(u, around_u_);
  tally_neighbours(v, around_v_);
  auto on_boundary = [](const std::vector<Neighbour>& around) {
    return std::any_of(around.begin(), around.end(),
                       [](const Neighbour& s) { return s.faces == 1; });
  };
  const bool u_boundary = on_boundary(around_u_);
  if (u_boundary != on_boundary(around_v_) || (u_boundary && shared_.size() != 1)) return -1;
  if (!keeps_the_sides(u, v)) return -1;

  if (!find_cancelled_faces(u, v)) return -1;
  // Link condition: every common neighbour spans a face with u and v.
  for (const Neighbour& s : around_u_) {
    if (s.vertex == v) continue;
    const bool common = std::any_of(around_v_.begin(), around_v_.end(),
                                    [&s](const Neighbour& t) { return t.vertex == s.vertex; });
    const bool opposite =
        std::any_of(shared_.begin(), shared_.end(), [&](int f) { return has_vertex(f, s.vertex); });
    if (common && !opposite) return -1;
  }

  const Eigen::Vector3d p = merged_centroid(clusters_[u], clusters_[v]);
  for (const std::vector<int>* faces : {&u_only_, &v_only_})
    for (int f : *faces)
      if (!is_cancelled(f) && !face_stays_sound(f, u, v, p)) return -1;
  // Needles: the worst face around the merged vertex may be below kMinFaceQuality only if it is no
  // worse than the worst face around u and v before, the faces the collapse removes included. A
  // rule per face locked islands of small clusters among large ones for good: merging one into a
  // neighbour removes the needles between them but makes its other faces a little thinner.
  if (star_quality(u, v, p, true) < std::min(kMinFaceQuality, star_quality(u, v, p, false)))
    return -1;
  collapse(u, v, p);
  return u;
}

// Whether face f = (v, p, q) and face g = (u, q, p), which the collapse of v into u lays on each
// other, are a sheet of no thickness: u and v on the same side of pq, and the four points in one
// plane (the volume they span within kSheetThickness of the cube of their longest distance;
// measured on the clusters' positions, not the faces' normals, which are noise on slivers). The
// two sides of a thin part are not, nor two faces of a flat surface on both sides of pq.
bool Simplifier::is_double_sheet(int u, int v, int p, int q) const {
  const Eigen::Vector3d &x = position_[u], &y = position_[v], &a = position_[p], &b = position_[q];
  const Eigen::Vector3d edge = b - a;
  if (edge.cross(x - a).dot(edge.cross(y - a)) <= 0) return false;
  const double longest = std::max({(x - y).norm(), (x - a).norm(), (x - b).norm(), (y - a).norm(),
                                   (y - b).norm(), edge.norm()});
  return std::abs((y - x).dot((a - x).cross(b - x))) <=
         kSheetThickness * longest * longest * longest;
}

// A face of v that the collapse lays on a face of u (the same three vertices once v is u): when
// the two are a sheet of no thickness already (is_double_sheet), they cancel, as copies in the
// input do; otherwise (a duplicate face, or the two sides of a thin part pressed together) the
// collapse is refused. So is one that leaves the merged vertex without a face. Fills cancelled_
// (with shared_, u_only_ and v_only_ set); false when the collapse is refused.
bool Simplifier::find_cancelled_faces(int u, int v) {
  cancelled_.clear();
  // The two vertices that follow x in face f, in f's cyclic order.
  const auto after = [this](int f, int x) {
    const int k = faces_(f, 0) == x ? 0 : faces_(f, 1) == x ? 1 : 2;
    return std::array<int, 2>{faces_(f, (k + 1) % 3), faces_(f, (k + 2) % 3)};
  };
  for (int f : v_only_) {
    const std::array<int, 2> after_v = after(f, v);
    for (int g : u_only_) {
      const std::array<int, 2> after_u = after(g, u);
      if (after_u == after_v) return false;
      if (after_u[0] == after_v[1] && after_u[1] == after_v[0] && !is_cancelled(g)) {
        if (!is_double_sheet(u, v, after_v[0], after_v[1])) return false;
        cancelled_.push_back(f);
        cancelled_.push_back(g);
        break;
      }
    }
  }
  return u_only_.size() + v_only_.size() > cancelled_.size();
}

// Sides, like the boundary: u and v on one side, both next to the other side or neither, and then
// merged along an edge of a face that reaches the other side (around_u_, around_v_, shared_ set).
bool Simplifier::keeps_the_sides(int u, int v) const {
  if (sides_.empty()) return true;
  if (!same_side(u, v)) return false;
  const auto next_to_other_side = [this](int x, const std::vector<Neighbour>& around) {
    return std::any_of(around.begin(), around.end(),
                       [&](const Neighbour& s) { return !same_side(x, s.vertex); });
  };
  const bool u_next = next_to_other_side(u, around_u_);
  if (u_next != next_to_other_side(v, around_v_)) return false;
  return !u_next || std::any_of(shared_.begin(), shared_.end(), [&](int f) {
    return !same_side(u, faces_(f, 0)) || !same_side(u, faces_(f, 1)) ||
           !same_side(u, faces_(f, 2));
  });
}

void Simplifier::collapse(int u, int v, const Eigen::Vector3d& p) {
  for (const std::vector<int>* faces : {&shared_, &cancelled_})
    for (int f : *faces) face_alive_[f] = 0;
  for (int f : v_only_) {
    if (!face_alive_[f]) continue;
    for (int k = 0; k < 3; ++k)
      if (faces_(f, k) == v) faces_(f, k) = u;
    vertex_faces_[u].push_back(f);
  }
  std::vector<int>().swap(vertex_faces_[v]);

  Cluster &a = clusters_[u], &b = clusters_[v];
  a.quadric += b.quadric;
  a.weighted_sum += b.weighted_sum;
  a.plain_sum += b.plain_sum;
  a.mass += b.mass;
  a.count += b.count;
  position_[u] = p;
  alive_[v] = 0;
  merged_into_[v] = u;
  --num_alive_;
  ++version_[u];
  // A vertex whose faces all cancelled leaves the mesh; its fine vertices belong to no cluster.
  for (int f : cancelled_)
    for (int k = 0; k < 3; ++k) {
      const int w = faces_(f, k);
      if (alive_[w] && live_faces(w).empty()) {
        alive_[w] = 0;
        --num_alive_;
      }
    }
}

// Far above the target, collapses go in rounds: every live edge's candidate, sorted by cost; the
// cheaper half is collapsed in that order, skipping the edges of a vertex that grew earlier in the
// round (a cost depends only on the edge's two clusters, so the others are up to date). A round
// costs a sort and a sweep instead of heap operations with cache misses per candidate and the
// candidates pushed again after every collapse (bench/results/native.json, BM_GhostMesh). The heap
// then finishes in the exact greedy order near the target.
void Simplifier::collapse_in_rounds(int until, const std::function<void()>& report) {
  std::vector<Candidate> round;
  std::vector<int> locked(alive_.size(), -1);  // the last round each vertex grew in
  for (int r = 0; num_alive_ > until; ++r) {
    round.clear();
    for (int x = 0; x < static_cast<int>(alive_.size()); ++x)
      if (alive_[x]) add_candidates(x, true, round);
    std::sort(round.begin(), round.end(),
              [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
    int collapses = 0;
    for (size_t i = 0; i < round.size() / 2 && num_alive_ > until; ++i) {
      const Candidate& c = round[i];
      if (locked[c.u] == r || locked[c.v] == r || !alive_[c.u] || !alive_[c.v]) continue;
      const int kept = try_collapse(c.u, c.v);
      if (kept < 0) continue;
      ++collapses;
      locked[kept] = r;
      report();
    }
    if (collapses == 0) break;
  }
}

void Simplifier::simplify(int target, Progress* progress) {
  if (progress) progress->report(stages::kGhost, 0.0);
  if (num_alive_ <= target) return;
  const int start = num_alive_;
  long pops = 0;
  auto report = [&] {
    if (progress && ++pops % kReportInterval == 0)
      progress->report(stages::kGhost, double(start - num_alive_) / double(start - target));
  };
  collapse_in_rounds(target < num_alive_ / kRoundsAbove ? kRoundsAbove * target : num_alive_,
                     report);
  seed();
  int collapses_in_pass = 0;
  while (num_alive_ > target) {
    // A rejected candidate returns only when one of its vertices changes; a fresh pass over all
    // edges catches those whose neighbourhood changed instead.
    if (heap_.empty()) {
      if (collapses_in_pass == 0) break;
      collapses_in_pass = 0;
      seed();
      continue;
    }
    const Candidate c = heap_.top();
    heap_.pop();
    report();
    if (!alive_[c.u] || !alive_[c.v] || version_[c.u] != c.version_u ||
        version_[c.v] != c.version_v)
      continue;
    const int kept = try_collapse(c.u, c.v);
    if (kept < 0) continue;
    ++collapses_in_pass;
    push_edges(kept, false);
  }
}

EdgeCollapse Simplifier::result() {
  const int n = static_cast<int>(alive_.size());
  std::vector<int> id(n, -1);
  EdgeCollapse out;
  out.V.resize(num_alive_, 3);
  for (int x = 0, next = 0; x < n; ++x)
    if (alive_[x]) {
      out.V.row(next) = position_[x].transpose();
      id[x] = next++;
    }
  out.cluster.resize(n);
  for (int x = 0; x < n; ++x) {
    int root = x;
    while (merged_into_[root] >= 0) root = merged_into_[root];
    for (int y = x; merged_into_[y] >= 0;) {  // path compression
      const int next = merged_into_[y];
      if (next != root) merged_into_[y] = root;
      y = next;
    }
    out.cluster[x] = id[root];
  }
  const int num_faces = static_cast<int>(std::count(face_alive_.begin(), face_alive_.end(), 1));
  out.F.resize(num_faces, 3);
  for (int f = 0, next = 0; f < static_cast<int>(face_alive_.size()); ++f)
    if (face_alive_[f]) {
      for (int k = 0; k < 3; ++k) out.F(next, k) = id[faces_(f, k)];
      ++next;
    }
  return out;
}

}  // namespace

EdgeCollapse collapse_edges(const VerticesRef& V, const FacesRef& F, const VectorRef& mass,
                            int target, Progress* progress, const std::vector<char>& sides) {
  validate_mesh(V, F);
  if (target < 4)
    throw InputError(message("target: a ghost needs at least 4 vertices, got ", target));
  if (mass.size() != V.rows())
    throw InputError(
        message("mass: expected ", V.rows(), " values (one per vertex), got ", mass.size()));
  for (Eigen::Index i = 0; i < mass.size(); ++i)
    if (!std::isfinite(mass[i]) || mass[i] < 0)
      throw InputError(message("mass[", i, "]: expected a finite value >= 0, got ", mass[i]));
  if (!sides.empty() && static_cast<Eigen::Index>(sides.size()) != V.rows())
    throw InputError(
        message("sides: expected ", V.rows(), " values (one per vertex), got ", sides.size()));

  if (target >= V.rows()) {
    if (progress) progress->report(stages::kGhost, 1.0);
    EdgeCollapse identity{V, F,
                          Eigen::VectorXi::LinSpaced(V.rows(), 0, static_cast<int>(V.rows()) - 1)};
    return identity;
  }
  Simplifier simplifier(V, F, mass, sides);
  simplifier.simplify(target, progress);
  return simplifier.result();
}

}  // namespace modal_deform
