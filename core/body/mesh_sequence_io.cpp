#include "core/body/mesh_sequence_io.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstring>
#include <limits>
#include <string>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// Ours (z up, facing +y, +x right) to glTF's (Y up, facing +Z): X = -x, Y = z, Z = y.
Eigen::Vector3f toGltf(const Eigen::Vector3f& v) {
  return {-v.x(), v.z(), v.y()};
}

// The binary chunk of a GLB, and the glTF JSON arrays that describe it.
class GlbBuilder {
 public:
  // Appends `bytes` (4-byte aligned) as a buffer view; returns its index.
  int addView(const void* bytes, size_t size, int target) {
    const size_t offset = bin_.size();
    bin_.resize(offset + ((size + 3) & ~size_t{3}), '\0');
    std::memcpy(bin_.data() + offset, bytes, size);
    views_ += fmt::format("{}{{\"buffer\": 0, \"byteOffset\": {}, \"byteLength\": {}{}}}",
                          view_count_ ? ", " : "", offset, size,
                          target ? fmt::format(", \"target\": {}", target) : "");
    return view_count_++;
  }
  // An accessor over a whole view; `minmax` is "" or ", \"min\": [...], \"max\": [...]".
  int addAccessor(int view, int component_type, size_t count, const char* type,
                  const std::string& minmax = "") {
    accessors_ += fmt::format(
        "{}{{\"bufferView\": {}, \"componentType\": {}, \"count\": {}, \"type\": \"{}\"{}}}",
        accessor_count_ ? ", " : "", view, component_type, count, type, minmax);
    return accessor_count_++;
  }
  int addFloats(const std::vector<float>& values, const char* type, int components, int target,
                bool with_minmax) {
    std::string minmax;
    if (with_minmax) {
      std::vector<float> lo(components, std::numeric_limits<float>::max()),
          hi(components, std::numeric_limits<float>::lowest());
      for (size_t i = 0; i < values.size(); ++i) {
        lo[i % components] = std::min(lo[i % components], values[i]);
        hi[i % components] = std::max(hi[i % components], values[i]);
      }
      minmax =
          fmt::format(", \"min\": [{}], \"max\": [{}]", fmt::join(lo, ", "), fmt::join(hi, ", "));
    }
    const int view = addView(values.data(), values.size() * sizeof(float), target);
    return addAccessor(view, 5126, values.size() / components, type, minmax);
  }

  std::string glb(const std::string& rest_of_json) const {
    std::string json = fmt::format(
        "{{\"asset\": {{\"version\": \"2.0\", \"generator\": \"Lumistage\"}}, "
        "\"buffers\": [{{\"byteLength\": {}}}], \"bufferViews\": [{}], \"accessors\": [{}], {}}}",
        bin_.size(), views_, accessors_, rest_of_json);
    json.resize((json.size() + 3) & ~size_t{3}, ' ');
    const uint32_t total = uint32_t(12 + 8 + json.size() + 8 + bin_.size());
    std::string out;
    out.reserve(total);
    auto u32 = [&out](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(0x46546C67);  // "glTF"
    u32(2);
    u32(total);
    u32(uint32_t(json.size()));
    u32(0x4E4F534A);  // "JSON"
    out += json;
    u32(uint32_t(bin_.size()));
    u32(0x004E4942);  // "BIN\0"
    out += bin_;
    return out;
  }

 private:
  std::string bin_, views_, accessors_;
  int view_count_ = 0, accessor_count_ = 0;
};

}  // namespace

void saveMeshPly(const fs::path& path, const TriangleMesh& mesh) {
  std::string data = fmt::format(
      "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float "
      "y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
      mesh.vertexCount(), mesh.triangles.size());
  const size_t header = data.size();
  data.resize(header + size_t(mesh.vertexCount()) * 12 + mesh.triangles.size() * 13);
  char* out = data.data() + header;
  for (int v = 0; v < mesh.vertexCount(); ++v, out += 12)
    std::memcpy(out, mesh.positions.col(v).data(), 12);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    *out++ = 3;
    std::memcpy(out, t.data(), 12);
    out += 12;
  }
  writeFileAtomically(path, data);
}

void saveMeshObj(const fs::path& path, const TriangleMesh& mesh) {
  const bool normals = mesh.normals.cols() == mesh.positions.cols();
  std::string data = "# Lumistage: metres, z up\n";
  data.reserve(size_t(mesh.vertexCount()) * 70 + mesh.triangles.size() * 40);
  for (int v = 0; v < mesh.vertexCount(); ++v) {
    const auto p = mesh.positions.col(v);
    data += fmt::format("v {} {} {}\n", p.x(), p.y(), p.z());
  }
  for (int v = 0; normals && v < mesh.vertexCount(); ++v) {
    const auto n = mesh.normals.col(v);
    data += fmt::format("vn {} {} {}\n", n.x(), n.y(), n.z());
  }
  for (const Eigen::Vector3i& t : mesh.triangles) {
    if (normals) {
      data += fmt::format("f {0}//{0} {1}//{1} {2}//{2}\n", t.x() + 1, t.y() + 1, t.z() + 1);
    } else {
      data += fmt::format("f {} {} {}\n", t.x() + 1, t.y() + 1, t.z() + 1);
    }
  }
  writeFileAtomically(path, data);
}

void saveMeshSequenceGlb(const fs::path& path, const std::vector<TriangleMesh>& frames,
                         double fps) {
  if (frames.empty()) throw Error(path.string() + ": no frames to write");
  if (!(fps > 0)) throw Error(path.string() + fmt::format(": fps must be positive, got {}", fps));
  GlbBuilder glb;
  std::string meshes, nodes, samplers, channels, children;
  int shared_indices = -1;
  for (size_t f = 0; f < frames.size(); ++f) {
    const TriangleMesh& mesh = frames[f];
    for (const Eigen::Vector3i& t : mesh.triangles) {
      if (t.minCoeff() < 0 || t.maxCoeff() >= mesh.vertexCount())
        throw Error(path.string() + fmt::format(": frame {} has a triangle with a vertex out of "
                                                "range (it has {} vertices)",
                                                f, mesh.vertexCount()));
    }
    std::vector<float> positions(size_t(mesh.vertexCount()) * 3), normals;
    for (int v = 0; v < mesh.vertexCount(); ++v)
      Eigen::Vector3f::Map(&positions[3 * v]) = toGltf(mesh.positions.col(v));
    std::string attributes =
        fmt::format("\"POSITION\": {}", glb.addFloats(positions, "VEC3", 3, 34962, true));
    if (mesh.normals.cols() == mesh.positions.cols()) {
      normals.resize(positions.size());
      for (int v = 0; v < mesh.vertexCount(); ++v)
        Eigen::Vector3f::Map(&normals[3 * v]) = toGltf(mesh.normals.col(v));
      attributes +=
          fmt::format(", \"NORMAL\": {}", glb.addFloats(normals, "VEC3", 3, 34962, false));
    }
    int indices = shared_indices;
    if (indices < 0 || mesh.triangles != frames[0].triangles) {
      const int view = glb.addView(mesh.triangles.data(), mesh.triangles.size() * 12, 34963);
      indices = glb.addAccessor(view, 5125, mesh.triangles.size() * 3, "SCALAR");
      if (f == 0) shared_indices = indices;
    }
    meshes += fmt::format(
        "{}{{\"name\": \"frame_{:06}\", \"primitives\": [{{\"attributes\": {{{}}}, \"indices\": "
        "{}, \"mode\": 4}}]}}",
        f ? ", " : "", f, attributes, indices);
    // Shown from its time to the next frame's.
    std::vector<float> times, scales;
    auto key = [&](double t, float s) {
      times.push_back(float(t));
      scales.insert(scales.end(), {s, s, s});
    };
    if (f > 0) key(0, 0);
    key(f / fps, 1);
    if (f + 1 < frames.size()) key((f + 1) / fps, 0);
    const int input = glb.addFloats(times, "SCALAR", 1, 0, true);
    const int output = glb.addFloats(scales, "VEC3", 3, 0, false);
    const float initial = f == 0 ? 1.0f : 0.0f;
    nodes += fmt::format("{}{{\"name\": \"frame_{:06}\", \"mesh\": {}, \"scale\": [{}, {}, {}]}}",
                         f ? ", " : "", f, f, initial, initial, initial);
    samplers += fmt::format("{}{{\"input\": {}, \"output\": {}, \"interpolation\": \"STEP\"}}",
                            f ? ", " : "", input, output);
    channels +=
        fmt::format("{}{{\"sampler\": {}, \"target\": {{\"node\": {}, \"path\": \"scale\"}}}}",
                    f ? ", " : "", f, f);
    children += fmt::format("{}{}", f ? ", " : "", f);
  }
  const size_t root = frames.size();
  const std::string json = fmt::format(
      "\"meshes\": [{}], \"nodes\": [{}, {{\"name\": \"lumistage_capture\", \"children\": [{}]}}], "
      "\"scenes\": [{{\"nodes\": [{}]}}], \"scene\": 0, \"animations\": [{{\"name\": "
      "\"capture\", \"samplers\": [{}], \"channels\": [{}]}}]",
      meshes, nodes, children, root, samplers, channels);
  writeFileAtomically(path, glb.glb(json));
}

}  // namespace lumistage
