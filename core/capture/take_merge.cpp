#include "core/capture/take_merge.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <memory>
#include <set>

#include "core/base/error.h"
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

TakeMergeReport mergeTake(const std::vector<fs::path>& parts, const fs::path& out,
                          const std::optional<Rig>& rig,
                          const std::function<void(int, int)>& progress) {
  if (parts.empty()) throw Error("take: no parts to merge");
  std::vector<std::unique_ptr<SessionReader>> readers;
  for (const fs::path& part : parts) readers.push_back(std::make_unique<SessionReader>(part));
  const SessionReader& first = *readers.front();

  // Every camera once, at its place in the merged rig: (part, camera in the part).
  std::map<std::string, std::pair<size_t, int>> owner;
  std::vector<Camera> cameras;
  std::vector<RigNode> nodes;
  for (size_t p = 0; p < readers.size(); ++p) {
    const SessionReader& r = *readers[p];
    if (r.pixelFormat() != first.pixelFormat() || r.fps() != first.fps()) {
      throw Error(fmt::format("take: {}: {} at {} fps, but {} is {} at {} fps", parts[p].string(),
                              pixelFormatName(r.pixelFormat()), r.fps(), parts[0].string(),
                              pixelFormatName(first.pixelFormat()), first.fps()));
    }
    for (int c = 0; c < r.rig().cameraCount(); ++c) {
      const std::string& name = r.rig().camera(c).name();
      if (const auto it = owner.find(name); it != owner.end()) {
        throw Error("take: camera " + name + " is in both " + parts[it->second.first].string() +
                    " and " + parts[p].string());
      }
      owner[name] = {p, c};
    }
    for (RigNode node : r.rig().nodes()) {
      for (int& c : node.cameras) c += static_cast<int>(cameras.size());
      nodes.push_back(std::move(node));
    }
    for (const Camera& camera : r.rig().cameras()) cameras.push_back(camera);
  }
  Rig merged_rig;
  if (rig) {
    std::set<std::string> names;
    for (const Camera& camera : rig->cameras()) {
      if (!owner.count(camera.name()))
        throw Error("take: the rig's camera " + camera.name() + " is in none of the parts");
      names.insert(camera.name());
    }
    for (const auto& [name, where] : owner) {
      if (!names.count(name))
        throw Error("take: camera " + name + " of " + parts[where.first].string() +
                    " is not in the rig");
    }
    merged_rig = *rig;
  } else {
    merged_rig = Rig(std::move(cameras), std::move(nodes));
  }

  // The frames every part holds.
  std::vector<std::map<int64_t, int>> index(readers.size());  // frame id -> frame in the part
  for (size_t p = 0; p < readers.size(); ++p) {
    for (int i = 0; i < readers[p]->frameCount(); ++i) index[p][readers[p]->frameId(i)] = i;
  }
  std::vector<int64_t> common;
  for (const auto& [id, i] : index[0]) {
    bool everywhere = true;
    for (size_t p = 1; p < readers.size(); ++p) everywhere = everywhere && index[p].count(id);
    if (everywhere) common.push_back(id);
  }
  if (common.empty()) {
    throw Error(fmt::format("take: the {} parts have no frame in common (first part: {})",
                            parts.size(), parts[0].string()));
  }
  TakeMergeReport report;
  for (size_t p = 0; p < readers.size(); ++p) {
    const size_t extra = index[p].size() - common.size();
    if (extra > 0) {
      report.notes.push_back(fmt::format("{}: {} of its {} frames are not in every part, left out",
                                         parts[p].string(), extra, index[p].size()));
    }
  }

  SessionWriter writer(out, merged_rig, first.pixelFormat(), first.fps(),
                       fmt::format("take of {} parts", parts.size()));
  std::vector<std::vector<CameraFrame>> frames(readers.size());
  std::vector<ImageView> views(merged_rig.cameraCount());
  const int64_t start_ns = first.timestampNs(index[0].at(common.front()));
  for (size_t f = 0; f < common.size(); ++f) {
    for (size_t p = 0; p < readers.size(); ++p)
      readers[p]->readFrame(index[p].at(common[f]), frames[p]);
    for (int c = 0; c < merged_rig.cameraCount(); ++c) {
      const auto [p, k] = owner.at(merged_rig.camera(c).name());
      views[c] = frames[p][k].image.view();
    }
    writer.writeFrame(common[f], first.timestampNs(index[0].at(common[f])) - start_ns, views);
    if (progress) progress(static_cast<int>(f) + 1, static_cast<int>(common.size()));
  }
  report.frames = writer.framesWritten();
  report.bytes = writer.bytesWritten();
  return report;
}

}  // namespace lumistage
