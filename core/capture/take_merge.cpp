#include "core/capture/take_merge.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "core/base/error.h"
#include "core/body/ply_mesh.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_writer.h"

namespace lumistage {

namespace fs = std::filesystem;

std::vector<fs::path> takeParts(const std::vector<fs::path>& paths) {
  std::vector<fs::path> parts;
  for (const fs::path& path : paths) {
    if (fs::exists(path / "session.yaml")) {
      parts.push_back(path);
      continue;
    }
    if (!fs::is_directory(path)) throw Error("take: " + path.string() + ": no such folder");
    const size_t before = parts.size();
    for (const fs::directory_entry& entry : fs::directory_iterator(path)) {
      if (entry.is_directory() && fs::exists(entry.path() / "session.yaml"))
        parts.push_back(entry.path());
    }
    if (parts.size() == before) {
      throw Error("take: " + path.string() +
                  ": neither a session (no session.yaml) nor a folder of sessions");
    }
  }
  std::sort(parts.begin(), parts.end());
  return parts;
}

namespace {

// The cameras' names of a part, in its order.
std::vector<std::string> cameraNames(const Rig& rig) {
  std::vector<std::string> names;
  for (const Camera& camera : rig.cameras()) names.push_back(camera.name());
  return names;
}

using Readers = std::vector<std::unique_ptr<SessionReader>>;

// The parts grouped by their cameras (a node's part and its continuations after a restart form a
// group; every camera is in one group), each camera's place in the merged rig (group, camera in
// it), and the rig the groups make together (their cameras and nodes in path order).
struct PartGroups {
  std::vector<std::vector<size_t>> groups;  // parts, in path order
  std::map<std::string, std::pair<size_t, int>> owner;
  std::vector<Camera> cameras;
  std::vector<RigNode> nodes;
};

PartGroups groupParts(const Readers& readers, const std::vector<fs::path>& parts) {
  const SessionReader& first = *readers.front();
  PartGroups out;
  for (size_t p = 0; p < readers.size(); ++p) {
    const SessionReader& r = *readers[p];
    if (r.pixelFormat() != first.pixelFormat() || r.fps() != first.fps() ||
        r.imageFiles() != first.imageFiles()) {
      throw Error(fmt::format(
          "take: {}: {} at {} fps in {} files, but {} is {} at {} fps in {} files",
          parts[p].string(), pixelFormatName(r.pixelFormat()), r.fps(),
          imageFilesName(r.imageFiles()), parts[0].string(), pixelFormatName(first.pixelFormat()),
          first.fps(), imageFilesName(first.imageFiles())));
    }
    const std::vector<std::string> names = cameraNames(r.rig());
    size_t g = 0;
    while (g < out.groups.size() && cameraNames(readers[out.groups[g].front()]->rig()) != names)
      ++g;
    if (g < out.groups.size()) {
      out.groups[g].push_back(p);
      continue;
    }
    for (size_t k = 0; k < names.size(); ++k) {
      if (const auto it = out.owner.find(names[k]); it != out.owner.end()) {
        throw Error("take: camera " + names[k] + " is in both " +
                    parts[out.groups[it->second.first].front()].string() + " and " +
                    parts[p].string() + " with other cameras");
      }
      out.owner[names[k]] = {out.groups.size(), static_cast<int>(k)};
    }
    out.groups.push_back({p});
    for (RigNode node : r.rig().nodes()) {
      for (int& c : node.cameras) c += static_cast<int>(out.cameras.size());
      out.nodes.push_back(std::move(node));
    }
    for (const Camera& camera : r.rig().cameras()) out.cameras.push_back(camera);
  }
  return out;
}

// The merged session's rig: `rig` where given (it must hold exactly the parts' cameras, at the
// sizes they filmed), else the parts' own cameras and nodes.
Rig mergedRig(const Readers& readers, const std::vector<fs::path>& parts, PartGroups& grouped,
              const std::optional<Rig>& rig) {
  if (!rig) {
    Rig merged(std::move(grouped.cameras), std::move(grouped.nodes));
    merged.setStage(readers.front()->rig().stage());  // every node records the rig's stage
    return merged;
  }
  std::set<std::string> names;
  for (const Camera& camera : rig->cameras()) {
    if (!grouped.owner.count(camera.name()))
      throw Error("take: the rig's camera " + camera.name() + " is in none of the parts");
    // The parts' images are what they are: a rig of another size would make a session no
    // reader opens.
    const auto [group, k] = grouped.owner.at(camera.name());
    const Camera& filmed = readers[grouped.groups[group].front()]->rig().camera(k);
    if (filmed.width() != camera.width() || filmed.height() != camera.height()) {
      throw Error(fmt::format("take: the rig's camera {} is {}x{}, its part filmed {}x{}",
                              camera.name(), camera.width(), camera.height(), filmed.width(),
                              filmed.height()));
    }
    names.insert(camera.name());
  }
  for (const auto& [name, where] : grouped.owner) {
    if (!names.count(name))
      throw Error("take: camera " + name + " of " +
                  parts[grouped.groups[where.first].front()].string() + " is not in the rig");
  }
  return *rig;
}

// Per group, every frame its parts hold: frame id -> (part, frame in the part); and each part's
// timestamp offset. A part's timestamps count from its own start: a continuation's are moved to
// follow the part before it at the session's rate across the frames between them. Empty parts
// leave their groups.
struct FrameIndex {
  std::vector<std::map<int64_t, std::pair<size_t, int>>> frames;
  std::vector<int64_t> offset_ns;
};

FrameIndex indexFrames(const Readers& readers, std::vector<std::vector<size_t>>& groups) {
  const double fps = readers.front()->fps();
  FrameIndex out;
  out.frames.resize(groups.size());
  out.offset_ns.assign(readers.size(), 0);
  for (size_t g = 0; g < groups.size(); ++g) {
    std::vector<size_t>& group = groups[g];
    std::erase_if(group, [&](size_t p) { return readers[p]->frameCount() == 0; });
    if (group.empty()) continue;
    std::sort(group.begin(), group.end(),
              [&](size_t a, size_t b) { return readers[a]->frameId(0) < readers[b]->frameId(0); });
    for (size_t k = 1; k < group.size(); ++k) {
      const SessionReader& before = *readers[group[k - 1]];
      const SessionReader& part = *readers[group[k]];
      const int last = before.frameCount() - 1;
      out.offset_ns[group[k]] =
          out.offset_ns[group[k - 1]] + before.timestampNs(last) - part.timestampNs(0) +
          std::llround(double(part.frameId(0) - before.frameId(last)) * 1e9 / fps);
    }
    for (const size_t p : group) {
      for (int i = 0; i < readers[p]->frameCount(); ++i)
        out.frames[g].emplace(readers[p]->frameId(i), std::make_pair(p, i));  // the earlier part's
    }
  }
  return out;
}

// The frames every group holds; a note for each group's frames left out.
std::vector<int64_t> commonFrames(const FrameIndex& index,
                                  const std::vector<std::vector<size_t>>& groups,
                                  const std::vector<fs::path>& parts, TakeMergeReport& report) {
  std::vector<int64_t> common;
  for (const auto& [id, where] : index.frames[0]) {
    bool everywhere = true;
    for (size_t g = 1; g < groups.size(); ++g) everywhere = everywhere && index.frames[g].count(id);
    if (everywhere) common.push_back(id);
  }
  if (common.empty()) {
    throw Error(fmt::format("take: the {} parts have no frame in common (first part: {})",
                            parts.size(), parts[0].string()));
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    const size_t extra = index.frames[g].size() - common.size();
    if (extra > 0) {
      report.notes.push_back(fmt::format("{}: {} of its {} frames are not in every part, left out",
                                         parts[groups[g].front()].string(), extra,
                                         index.frames[g].size()));
    }
  }
  return common;
}

}  // namespace

TakeMergeReport mergeTake(const std::vector<fs::path>& parts, const fs::path& out,
                          const std::optional<Rig>& rig, std::optional<ImageFiles> files,
                          const std::function<void(int, int)>& progress) {
  if (parts.empty()) throw Error("take: no parts to merge");
  Readers readers;
  for (const fs::path& part : parts) readers.push_back(std::make_unique<SessionReader>(part));
  const SessionReader& first = *readers.front();
  PartGroups grouped = groupParts(readers, parts);
  const Rig merged_rig = mergedRig(readers, parts, grouped, rig);
  std::vector<std::vector<size_t>>& groups = grouped.groups;
  const auto& owner = grouped.owner;
  const FrameIndex frame_index = indexFrames(readers, groups);
  const auto& index = frame_index.frames;
  const auto& offset_ns = frame_index.offset_ns;
  TakeMergeReport report;
  const std::vector<int64_t> common = commonFrames(frame_index, groups, parts, report);

  const ImageFiles out_files = files.value_or(first.imageFiles());
  const bool copy = out_files == first.imageFiles();
  // Written beside `out` and put in its place once whole: a merge cut short (a full disk, an
  // interrupted run) left a shorter session under the name that opened without a word.
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_empty(out, ec))
    throw Error(out.string() +
                ": already exists and is not empty; a session is never written "
                "over another");
  // An empty folder given (a mount point, a folder made for it): written in place, and emptied
  // again if the merge fails; else beside it ("out/" taken as "out").
  const bool in_place = fs::is_directory(out, ec);
  fs::path named = out.lexically_normal();
  if (!named.has_filename()) named = named.parent_path();
  const fs::path partial =
      in_place ? out : named.parent_path() / (named.filename().string() + ".partial");
  if (!in_place && fs::exists(partial, ec))
    throw Error(partial.string() + ": left by a merge that did not finish; remove it first");
  struct RemovePartial {
    const fs::path& path;
    bool keep_folder;
    bool done = false;
    ~RemovePartial() {
      if (done) return;
      std::error_code ignored;  // the parts are whole: nothing is lost
      if (!keep_folder) {
        fs::remove_all(path, ignored);
        return;
      }
      for (const fs::directory_entry& entry : fs::directory_iterator(path, ignored))
        fs::remove_all(entry.path(), ignored);
    }
  } remove_partial{partial, in_place};
  // A session merged alone (a virtual studio's, its images made PNM) keeps its ground truth; a
  // take's parts, from the nodes, have none.
  const bool truth = readers.size() == 1 && first.hasTruth();
  std::vector<std::string> joint_names;
  std::vector<std::vector<Eigen::Vector3d>> joints;
  if (truth) joints = first.readTruthJoints(&joint_names);
  SessionWriter writer(partial, merged_rig, first.pixelFormat(), first.fps(),
                       fmt::format("take of {} parts", parts.size()), joint_names, out_files);
  std::vector<fs::path> paths(merged_rig.cameraCount());
  std::vector<std::vector<CameraFrame>> decoded(groups.size());  // per group, when not copying
  std::vector<ImageView> views(merged_rig.cameraCount());
  std::vector<std::pair<size_t, int>> source(merged_rig.cameraCount());  // (group, camera in it)
  for (int c = 0; c < merged_rig.cameraCount(); ++c)
    source[c] = owner.at(merged_rig.camera(c).name());
  std::vector<std::vector<uint8_t>> masks(truth ? merged_rig.cameraCount() : 0);
  TriangleMesh surface;
  FrameTruth frame_truth;
  // A frame's truth, in the merged rig's camera order (nullptr without).
  auto truthOf = [&](int64_t id) -> const FrameTruth* {
    if (!truth) return nullptr;
    const int i = index[0].at(id).second;
    // Joints always; masks and the surface where the session has them.
    const bool has_masks = fs::exists(first.truthMaskPath(0, i));
    for (int c = 0; has_masks && c < merged_rig.cameraCount(); ++c)
      masks[c] = first.readTruthMask(source[c].second, i);
    const fs::path ply = first.folder() / "truth" / "surface" / fmt::format("{:06}.ply", id);
    const bool has_surface = fs::exists(ply);
    if (has_surface) surface = readPlyMesh(ply);
    frame_truth = {joints[size_t(i)], has_surface ? &surface : nullptr,
                   has_masks ? &masks : nullptr};
    return &frame_truth;
  };
  // Timestamps: the first group's, from the first common frame.
  auto timestamp = [&](int64_t id) {
    const auto [p, i] = index[0].at(id);
    return readers[p]->timestampNs(i) + offset_ns[p];
  };
  const int64_t start_ns = timestamp(common.front());
  for (size_t f = 0; f < common.size(); ++f) {
    if (copy) {
      // The parts' files as they are (checked when their readers opened them): no decoding.
      for (int c = 0; c < merged_rig.cameraCount(); ++c) {
        const auto [g, k] = source[c];
        const auto [p, i] = index[g].at(common[f]);
        paths[c] = readers[p]->imagePath(k, i);
      }
      writer.copyFrame(common[f], timestamp(common[f]) - start_ns, paths, truthOf(common[f]));
    } else {
      for (size_t g = 0; g < groups.size(); ++g) {
        const auto [p, i] = index[g].at(common[f]);
        readers[p]->readFrame(i, decoded[g]);
      }
      for (int c = 0; c < merged_rig.cameraCount(); ++c)
        views[c] = decoded[source[c].first][source[c].second].image.view();
      writer.writeFrame(common[f], timestamp(common[f]) - start_ns, views, truthOf(common[f]));
    }
    if (progress) progress(static_cast<int>(f) + 1, static_cast<int>(common.size()));
  }
  report.frames = writer.framesWritten();
  report.bytes = writer.bytesWritten();
  if (!in_place) {
    fs::rename(partial, named, ec);
    if (ec)
      throw Error(fmt::format("{}: the merged session could not be put in place: {}",
                              named.string(), ec.message()));
  }
  remove_partial.done = true;
  return report;
}

}  // namespace lumistage
