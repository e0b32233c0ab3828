#include "mesh/read_mesh.h"

#include <zlib.h>

#include <memory>
#include <sstream>
#include <vector>

#include "util/errors.h"

namespace modal_deform {
namespace {

// Line reader over plain or gzip files (zlib reads both).
class LineReader {
 public:
  explicit LineReader(const std::string& path)
      : path_(path), file_(gzopen(path.c_str(), "rb"), gzclose) {
    if (!file_) throw InputError(message(path, ": cannot open the file"));
  }
  bool next(std::string& line) {
    line.clear();
    char buffer[4096];
    while (gzgets(file_.get(), buffer, sizeof buffer)) {
      line += buffer;
      if (!line.empty() && line.back() == '\n') break;
    }
    if (line.empty()) return false;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    ++number_;
    return true;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(message(path_, ":", number_, ": ", what));
  }

 private:
  std::string path_;
  std::unique_ptr<gzFile_s, int (*)(gzFile)> file_;
  int number_ = 0;
};

void add_polygon(const std::vector<int>& polygon, std::vector<int>& faces) {
  for (size_t k = 1; k + 1 < polygon.size(); ++k)
    faces.insert(faces.end(), {polygon[0], polygon[k], polygon[k + 1]});
}

TriangleMesh read_obj(LineReader& reader) {
  std::vector<double> positions;
  std::vector<int> faces, polygon;
  std::string line, tag, corner;
  while (reader.next(line)) {
    std::istringstream in(line);
    if (!(in >> tag)) continue;
    if (tag == "v") {
      double x, y, z;
      if (!(in >> x >> y >> z)) reader.fail("a vertex needs three coordinates");
      positions.insert(positions.end(), {x, y, z});
    } else if (tag == "f") {
      polygon.clear();
      while (in >> corner) {
        const long index = std::strtol(corner.c_str(), nullptr, 10);  // "7/3/2" reads as 7
        const long count = static_cast<long>(positions.size() / 3);
        const long zero_based = index < 0 ? count + index : index - 1;
        if (index == 0 || zero_based < 0 || zero_based >= count)
          reader.fail("face index out of range");
        polygon.push_back(static_cast<int>(zero_based));
      }
      if (polygon.size() < 3) reader.fail("a face needs at least three vertices");
      add_polygon(polygon, faces);
    }
  }
  return mesh_from_buffers(positions, faces);
}

TriangleMesh read_ply(LineReader& reader) {
  std::string line, word;
  long num_vertices = -1, num_faces = -1;
  int vertex_properties = 0;
  bool in_vertex_element = false;
  while (reader.next(line)) {
    std::istringstream in(line);
    in >> word;
    if (word == "format") {
      in >> word;
      if (word != "ascii") reader.fail("only ASCII PLY files are supported");
    } else if (word == "element") {
      in >> word;
      in_vertex_element = word == "vertex";
      long count;
      if (!(in >> count) || count < 0) reader.fail("bad element count");
      if (in_vertex_element)
        num_vertices = count;
      else if (word == "face")
        num_faces = count;
    } else if (word == "property" && in_vertex_element) {
      ++vertex_properties;
    } else if (word == "end_header") {
      break;
    }
  }
  if (num_vertices < 0 || num_faces < 0 || vertex_properties < 3)
    reader.fail("missing vertex or face element");
  std::vector<double> positions;
  positions.reserve(3 * num_vertices);
  for (long v = 0; v < num_vertices; ++v) {
    if (!reader.next(line)) reader.fail("file ends inside the vertex list");
    std::istringstream in(line);
    double x, y, z;
    if (!(in >> x >> y >> z)) reader.fail("a vertex needs three coordinates");
    positions.insert(positions.end(), {x, y, z});
  }
  std::vector<int> faces, polygon;
  for (long f = 0; f < num_faces; ++f) {
    if (!reader.next(line)) reader.fail("file ends inside the face list");
    std::istringstream in(line);
    long count, index;
    if (!(in >> count) || count < 3) reader.fail("a face needs at least three vertices");
    polygon.clear();
    for (long k = 0; k < count; ++k) {
      if (!(in >> index) || index < 0 || index >= num_vertices)
        reader.fail("face index out of range");
      polygon.push_back(static_cast<int>(index));
    }
    add_polygon(polygon, faces);
  }
  return mesh_from_buffers(positions, faces);
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

TriangleMesh read_mesh(const std::string& path) {
  std::string name = path;
  if (ends_with(name, ".gz")) name.resize(name.size() - 3);
  LineReader reader(path);
  if (ends_with(name, ".obj")) return read_obj(reader);
  if (ends_with(name, ".ply")) return read_ply(reader);
  throw InputError(message(path, ": unknown mesh format (expected .obj or .ply, optionally .gz)"));
}

}  // namespace modal_deform
