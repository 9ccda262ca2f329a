// lumistage-node: the headless worker on each camera PC. It owns the node's cameras (Aravis
// cameras, or its cameras of a recorded session), connects to the studio and does the node's part
// of every frame (core/pipeline/camera_node.h). Without --studio it checks its place in the rig.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <exception>
#include <thread>

#include "app/cli/checks.h"
#include "app/node/node_monitor.h"
#include "core/base/output_path.h"
#include "core/base/stop_signal.h"
#include "core/body/human_model.h"
#include "core/capture/aravis_source.h"
#include "core/capture/session_source.h"
#include "core/capture/virtual_gige_cameras.h"
#include "core/geometry/rig_file.h"
#include "core/net/curve_keys.h"
#include "core/pipeline/camera_node.h"

namespace {

// The command line's values.
struct NodeArgs {
  std::string rig_path, node_name, session, replay = "rate", studio, keys, address,
                                            pixel_format = "bayer_rggb8";
  std::vector<std::string> devices;
  double fps = 25;
  bool plain = false, monitor = false;
  std::string monitor_screenshot, takes;
  lumistage::BodyChoice body;
  std::string take_files = "pnm";
  double unattended_take_limit_s = 30;
  int plate_frames = 0;
};

void addNodeOptions(CLI::App& app, NodeArgs& a) {
  app.add_option("--rig", a.rig_path, "rig file (default with --session: the session's)");
  app.add_option("--node", a.node_name, "this node's name in the rig")->required();
  app.add_option("--session", a.session, "serve this node's cameras of a recorded session");
  app.add_option("--replay", a.replay,
                 "session pace: rate (as recorded, looping) or memory (decoded up front)")
      ->check(CLI::IsMember({"rate", "memory"}))
      ->capture_default_str();
  app.add_option("--address", a.address,
                 "live Aravis cameras: camera i of the rig at ADDRESS+i (as lumistage stream and "
                 "virtual-cameras)");
  app.add_option("--device", a.devices,
                 "or its cameras' devices one by one (address, serial or id), in rig order");
  app.add_option("--pixel-format", a.pixel_format, "of the Aravis cameras")->capture_default_str();
  app.add_option("--fps", a.fps, "frame rate asked of the Aravis cameras")->capture_default_str();
  app.add_option("--studio", a.studio, "the studio's endpoint, e.g. tcp://studio-pc:5570");
  lumistage::addBodyOption(app, a.body);
  app.add_option("--keys", a.keys,
                 "key store folder (lumistage keys init): this node's key and the studio's");
  app.add_option("--takes", a.takes,
                 "record the takes the studio asks for into this folder, on this PC "
                 "(TAKES/<take>/<node>/; lumistage session merge joins the nodes' parts)");
  app.add_option("--take-files", a.take_files,
                 "how takes store the images: pnm (raw pixels, keeps up with the cameras) or png "
                 "(about 30% smaller, 10 ms or more a 1024x768 image to encode)")
      ->check(CLI::IsMember({"pnm", "png"}))
      ->capture_default_str();
  app.add_option("--unattended-take-limit", a.unattended_take_limit_s,
                 "close an open take after this many seconds without word from the studio")
      ->capture_default_str();
  app.add_option("--plate-frames", a.plate_frames,
                 "a stage without a green screen: learn each camera's clean plate from its first N "
                 "frames, which must film the empty stage (the actor walks in after)")
      ->check(CLI::Range(0, 10000));
  app.add_flag("--plain", a.plain, "no encryption or authentication (a closed lab network only)");
  app.add_flag("--monitor", a.monitor,
               "open a small window on this PC: the node's cameras, silhouettes and counters");
  app.add_option("--monitor-screenshot", a.monitor_screenshot,
                 "with --monitor: save the window to this PNG once it shows every camera, then "
                 "stop");
}

// Without --studio: the node's place in the rig, checked and printed.
void printNodeCheck(const lumistage::Rig& rig, const lumistage::RigNode& node) {
  fmt::print("node {} ({}): {} cameras\n", node.name,
             node.host.empty() ? "no host assigned" : node.host, node.cameras.size());
  for (int c : node.cameras) {
    fmt::print("  {} {}x{}\n", rig.camera(c).name(), rig.camera(c).width(), rig.camera(c).height());
  }
  fmt::print(
      "configuration is valid; give --studio and the cameras (--address, --device or "
      "--session) to serve\n");
}

lumistage::CameraNodeOptions nodeOptions(const NodeArgs& a) {
  lumistage::CameraNodeOptions node_options;
  node_options.takes = a.takes;
  node_options.take_files = *lumistage::parseImageFiles(a.take_files);
  node_options.unattended_take_limit =
      std::chrono::milliseconds(static_cast<int64_t>(1000 * a.unattended_take_limit_s));
  node_options.fps = a.fps;
  node_options.plate_frames = a.plate_frames;
  return node_options;
}

// The node's cameras of --session; node_options takes the session's frame rate.
std::unique_ptr<lumistage::FrameSource> openSessionSource(
    const NodeArgs& a, const lumistage::Rig& rig, const lumistage::RigNode& node,
    lumistage::CameraNodeOptions& node_options) {
  lumistage::ReplayOptions options;
  options.mode = a.replay == "memory" ? lumistage::ReplayMode::kFromMemory
                                      : lumistage::ReplayMode::kRecordedRate;
  options.cameras = node.cameras;
  // Every node shows the same recorded instant at the same time, as triggered cameras do.
  options.synchronized = true;
  auto replay_source = std::make_unique<lumistage::SessionSource>(a.session, options);
  // The session's cameras are taken by their place in --rig: the same place must hold the same
  // camera (a take merged without --rig lists its cameras part after part), or the node keys
  // one camera's pictures with another's calibration.
  const lumistage::Rig& recorded = replay_source->reader().rig();
  for (int c : node.cameras) {
    const lumistage::Camera& want = rig.camera(c);
    const bool same = c < recorded.cameraCount() && recorded.camera(c).name() == want.name() &&
                      recorded.camera(c).width() == want.width() &&
                      recorded.camera(c).height() == want.height();
    if (same) continue;
    throw std::runtime_error(fmt::format(
        "--session {}: camera {} of --rig {} is {} ({}x{}), the session's is {}: replay a "
        "session recorded with this rig (lumistage session merge --rig {})",
        a.session, c, a.rig_path, want.name(), want.width(), want.height(),
        c < recorded.cameraCount()
            ? fmt::format("{} ({}x{})", recorded.camera(c).name(), recorded.camera(c).width(),
                          recorded.camera(c).height())
            : "missing",
        a.rig_path));
  }
  node_options.fps = replay_source->reader().fps();
  return replay_source;
}

// The node's live Aravis cameras, at --address or --device.
std::unique_ptr<lumistage::FrameSource> openAravisSource(const NodeArgs& a,
                                                         const lumistage::Rig& rig,
                                                         const lumistage::RigNode& node) {
  if (!a.devices.empty() && a.devices.size() != node.cameras.size()) {
    throw std::runtime_error(fmt::format("--device given {} times for the node's {} cameras",
                                         a.devices.size(), node.cameras.size()));
  }
  const std::optional<lumistage::PixelFormat> format = lumistage::parsePixelFormat(a.pixel_format);
  if (!format)
    throw std::runtime_error("--pixel-format: expected one of " + lumistage::pixelFormatNames());
  std::vector<lumistage::AravisCameraConfig> configs(rig.cameraCount());  // others' stay empty
  for (size_t k = 0; k < node.cameras.size(); ++k) {
    lumistage::AravisCameraConfig& config = configs[node.cameras[k]];
    config.device = a.devices.empty()
                        ? lumistage::VirtualGigeCameras::addressOf(a.address, node.cameras[k])
                        : a.devices[k];
    config.pixel_format = *format;
    config.frame_rate_hz = a.fps;
  }
  return std::make_unique<lumistage::AravisSource>(rig, configs);
}

std::unique_ptr<lumistage::FrameSource> openSource(const NodeArgs& a, const lumistage::Rig& rig,
                                                   const lumistage::RigNode& node,
                                                   lumistage::CameraNodeOptions& node_options) {
  if (!a.session.empty()) return openSessionSource(a, rig, node, node_options);
  if (!a.address.empty() || !a.devices.empty()) return openAravisSource(a, rig, node);
  throw std::runtime_error(
      "give the node's cameras: --session DIR, or --address / --device for Aravis cameras");
}

lumistage::NodeEndpointConfig endpointFor(const NodeArgs& a, const lumistage::RigNode& node) {
  lumistage::NodeEndpointConfig endpoint;
  endpoint.connect = a.studio;
  endpoint.name = node.name;
  if (a.plain) {
    endpoint.security = lumistage::TransportSecurity::kPlain;
  } else {
    if (a.keys.empty())
      throw std::runtime_error("give --keys DIR (or --plain on a closed network)");
    const lumistage::KeyStore store(a.keys);
    endpoint.node_key = store.nodeKey(node.name);
    endpoint.studio_public_key = store.studioPublicKey();
  }
  return endpoint;
}

// Runs the node until it is stopped or stops on its own, with its window on this thread under
// --monitor. The exit status: 0 when stopped as asked, 1 when it stopped on its own, 2 when the
// window could not run.
int serve(lumistage::CameraNode& camera_node, const NodeArgs& a, const lumistage::Rig& rig,
          const lumistage::RigNode& node) {
  // SIGINT, SIGTERM or SIGHUP: the node closes its take and stops (a second one ends it at once).
  std::atomic<bool>& stop = lumistage::stopOnSignals();
  fmt::print("node {}: {} cameras, serving {}\n", node.name, node.cameras.size(), a.studio);
  if (!a.takes.empty()) {
    // For the log (journalctl): where takes go, and the room there (the studio shows it too).
    const lumistage::DiskSpace disk = lumistage::diskSpaceAt(a.takes);
    fmt::print("node {}: takes go to {}{}\n", node.name, a.takes,
               disk.free_bytes >= 0 ? " (" + lumistage::bytesInWords(disk.free_bytes) + " free)"
                                    : std::string(" (its free space unknown)"));
  }
  std::fflush(stdout);
  // Whether the node stopped on its own (its source ended or failed), not as asked: a failure,
  // for `lumistage run` and systemd to see.
  std::atomic<bool> stopped_alone{false};
  if (a.monitor) {
    // The node works on its own threads; the window lives on this one (GLFW wants the main
    // thread). Closing the window stops the node.
    std::thread worker([&camera_node, &stop, &stopped_alone] {
      camera_node.run(stop);
      if (!stop.exchange(true)) stopped_alone = true;  // closes the window too
    });
    bool monitor_failed = false;
    try {
      lumistage::runNodeMonitor(camera_node, rig, node.name, stop, a.monitor_screenshot);
    } catch (const std::exception& e) {
      fmt::print(stderr, "lumistage-node: {}\n", e.what());
      monitor_failed = true;
    }
    stop = true;
    worker.join();
    if (monitor_failed) return 2;  // as asked it could not run (no display): not a clean stop
  } else {
    camera_node.run(stop);
    stopped_alone = !stop;
  }
  fmt::print("node {}: sent {} frame sets, {:.1f} MB\n", node.name, camera_node.setsSent(),
             camera_node.bytesSent() / 1e6);
  if (stopped_alone) {
    fmt::print(stderr, "lumistage-node: error: node {} stopped: {}\n", node.name,
               camera_node.sourceEnd());
    return 1;
  }
  return 0;
}

// The node, as the command line asks; its exit status.
int runNode(NodeArgs& a) {
  if (a.rig_path.empty() && !a.session.empty()) a.rig_path = a.session + "/rig.yaml";
  if (a.rig_path.empty()) throw std::runtime_error("give --rig (or --session)");
  const lumistage::Rig rig = lumistage::loadRig(a.rig_path);
  const std::optional<int> index = rig.findNode(a.node_name);
  if (!index) {
    std::string names;
    for (const auto& n : rig.nodes()) names += (names.empty() ? "" : ", ") + n.name;
    fmt::print(stderr, "lumistage-node: error: {}: no node '{}'; the rig's nodes are: {}\n",
               a.rig_path, a.node_name, names);
    return 1;
  }
  const lumistage::RigNode& node = rig.nodes()[*index];
  if (a.studio.empty()) {
    printNodeCheck(rig, node);
    return 0;
  }
  lumistage::CameraNodeOptions node_options = nodeOptions(a);
  std::unique_ptr<lumistage::FrameSource> source = openSource(a, rig, node, node_options);
  const lumistage::NodeEndpointConfig endpoint = endpointFor(a, node);
  lumistage::CameraNode camera_node(rig, node.name, std::move(source), endpoint,
                                    lumistage::loadBody(a.body), node_options);
  return serve(camera_node, a, rig, node);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Lumistage camera node: owns the cameras of one PC and does the node's part of every frame"};
  app.set_version_flag("--version", LUMISTAGE_VERSION);
  NodeArgs args;
  addNodeOptions(app, args);
  CLI11_PARSE(app, argc, argv);
  try {
    return runNode(args);
  } catch (const std::exception& e) {
    fmt::print(stderr, "lumistage-node: error: {}\n", e.what());
    return 1;
  }
}
