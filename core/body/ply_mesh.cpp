#include "core/body/ply_mesh.h"

#include <cstring>
#include <sstream>
#include <string>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {

TriangleMesh readPlyMesh(const std::filesystem::path& path) {
  const std::string data = readFile(path.string());
  const size_t end = data.find("end_header\n");
  if (data.rfind("ply\nformat binary_little_endian 1.0\n", 0) != 0 || end == std::string::npos)
    throw Error(path.string() + ": not a binary little-endian PLY");
  std::istringstream header(data.substr(0, end));
  std::string line;
  long vertices = -1, faces = -1;
  int vertex_properties = 0;
  bool in_vertex = false;
  while (std::getline(header, line)) {
    long n = 0;
    char name[32] = {};
    if (std::sscanf(line.c_str(), "element %31s %ld", name, &n) == 2) {
      in_vertex = std::strcmp(name, "vertex") == 0;
      (in_vertex ? vertices : faces) = n;
    } else if (in_vertex && line.rfind("property float ", 0) == 0) {
      ++vertex_properties;
    } else if (in_vertex && line.rfind("property", 0) == 0) {
      throw Error(path.string() + ": vertex properties other than float x, y, z");
    }
  }
  if (vertices < 0 || faces < 0 || vertex_properties != 3)
    throw Error(path.string() + ": expected 'element vertex' (float x, y, z) and 'element face'");
  size_t at = end + std::strlen("end_header\n");
  // Counts checked against the bytes there are before they are multiplied (a count near 2^63
  // wrapped the product into a small one).
  if (size_t(vertices) > data.size() / 12 || size_t(faces) > data.size() / 13 ||
      data.size() < at + size_t(vertices) * 12 + size_t(faces) * 13)
    throw Error(path.string() + ": shorter than its header says");
  TriangleMesh mesh;
  mesh.positions.resize(3, vertices);
  std::memcpy(mesh.positions.data(), data.data() + at, size_t(vertices) * 12);
  at += size_t(vertices) * 12;
  mesh.triangles.resize(faces);
  for (long f = 0; f < faces; ++f, at += 13) {
    if (static_cast<uint8_t>(data[at]) != 3)
      throw Error(path.string() + ": face " + std::to_string(f) + " is not a triangle");
    std::memcpy(mesh.triangles[f].data(), data.data() + at + 1, 12);
    for (int k = 0; k < 3; ++k) {
      if (mesh.triangles[f][k] < 0 || mesh.triangles[f][k] >= vertices)
        throw Error(path.string() + ": face " + std::to_string(f) + " has an index out of range");
    }
  }
  mesh.computeNormals();
  return mesh;
}

}  // namespace lumistage
