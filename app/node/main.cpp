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

int main(int argc, char** argv) {
  CLI::App app{
      "Lumistage camera node: owns the cameras of one PC and does the node's part of every frame"};
  app.set_version_flag("--version", LUMISTAGE_VERSION);
  std::string rig_path, node_name, session, replay = "rate", studio, keys, address,
                                            pixel_format = "bayer_rggb8";
  std::vector<std::string> devices;
  double fps = 25;
  bool plain = false, monitor = false;
  std::string monitor_screenshot, takes;
  lumistage::BodyChoice body;
  app.add_option("--rig", rig_path, "rig file (default with --session: the session's)");
  app.add_option("--node", node_name, "this node's name in the rig")->required();
  app.add_option("--session", session, "serve this node's cameras of a recorded session");
  app.add_option("--replay", replay,
                 "session pace: rate (as recorded, looping) or memory (decoded up front)")
      ->check(CLI::IsMember({"rate", "memory"}))
      ->capture_default_str();
  app.add_option("--address", address,
                 "live Aravis cameras: camera i of the rig at ADDRESS+i (as lumistage stream and "
                 "virtual-cameras)");
  app.add_option("--device", devices,
                 "or its cameras' devices one by one (address, serial or id), in rig order");
  app.add_option("--pixel-format", pixel_format, "of the Aravis cameras")->capture_default_str();
  app.add_option("--fps", fps, "frame rate asked of the Aravis cameras")->capture_default_str();
  app.add_option("--studio", studio, "the studio's endpoint, e.g. tcp://studio-pc:5570");
  lumistage::addBodyOption(app, body);
  app.add_option("--keys", keys,
                 "key store folder (lumistage keys init): this node's key and the studio's");
  app.add_option("--takes", takes,
                 "record the takes the studio asks for into this folder, on this PC "
                 "(TAKES/<take>/<node>/; lumistage session merge joins the nodes' parts)");
  std::string take_files = "pnm";
  app.add_option("--take-files", take_files,
                 "how takes store the images: pnm (raw pixels, keeps up with the cameras) or png "
                 "(about 30% smaller, 10 ms or more a 1024x768 image to encode)")
      ->check(CLI::IsMember({"pnm", "png"}))
      ->capture_default_str();
  double unattended_take_limit_s = 30;
  app.add_option("--unattended-take-limit", unattended_take_limit_s,
                 "close an open take after this many seconds without word from the studio")
      ->capture_default_str();
  app.add_flag("--plain", plain, "no encryption or authentication (a closed lab network only)");
  app.add_flag("--monitor", monitor,
               "open a small window on this PC: the node's cameras, silhouettes and counters");
  app.add_option("--monitor-screenshot", monitor_screenshot,
                 "with --monitor: save the window to this PNG once it shows every camera, then "
                 "stop");
  CLI11_PARSE(app, argc, argv);
  try {
    if (rig_path.empty() && !session.empty()) rig_path = session + "/rig.yaml";
    if (rig_path.empty()) throw std::runtime_error("give --rig (or --session)");
    const lumistage::Rig rig = lumistage::loadRig(rig_path);
    const std::optional<int> index = rig.findNode(node_name);
    if (!index) {
      std::string names;
      for (const auto& n : rig.nodes()) names += (names.empty() ? "" : ", ") + n.name;
      fmt::print(stderr, "lumistage-node: error: {}: no node '{}'; the rig's nodes are: {}\n",
                 rig_path, node_name, names);
      return 1;
    }
    const lumistage::RigNode& node = rig.nodes()[*index];
    if (studio.empty()) {
      fmt::print("node {} ({}): {} cameras\n", node.name,
                 node.host.empty() ? "no host assigned" : node.host, node.cameras.size());
      for (int c : node.cameras) {
        fmt::print("  {} {}x{}\n", rig.camera(c).name(), rig.camera(c).width(),
                   rig.camera(c).height());
      }
      fmt::print(
          "configuration is valid; give --studio and the cameras (--address, --device or "
          "--session) to serve\n");
      return 0;
    }
    std::unique_ptr<lumistage::FrameSource> source;
    lumistage::CameraNodeOptions node_options;
    node_options.takes = takes;
    node_options.take_files = *lumistage::parseImageFiles(take_files);
    node_options.unattended_take_limit =
        std::chrono::milliseconds(static_cast<int64_t>(1000 * unattended_take_limit_s));
    node_options.fps = fps;
    if (!session.empty()) {
      lumistage::ReplayOptions options;
      options.mode = replay == "memory" ? lumistage::ReplayMode::kFromMemory
                                        : lumistage::ReplayMode::kRecordedRate;
      options.cameras = node.cameras;
      // Every node shows the same recorded instant at the same time, as triggered cameras do.
      options.synchronized = true;
      auto replay_source = std::make_unique<lumistage::SessionSource>(session, options);
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
            session, c, rig_path, want.name(), want.width(), want.height(),
            c < recorded.cameraCount()
                ? fmt::format("{} ({}x{})", recorded.camera(c).name(), recorded.camera(c).width(),
                              recorded.camera(c).height())
                : "missing",
            rig_path));
      }
      node_options.fps = replay_source->reader().fps();
      source = std::move(replay_source);
    } else if (!address.empty() || !devices.empty()) {
      if (!devices.empty() && devices.size() != node.cameras.size()) {
        throw std::runtime_error(fmt::format("--device given {} times for the node's {} cameras",
                                             devices.size(), node.cameras.size()));
      }
      const std::optional<lumistage::PixelFormat> format =
          lumistage::parsePixelFormat(pixel_format);
      if (!format)
        throw std::runtime_error("--pixel-format: expected one of " +
                                 lumistage::pixelFormatNames());
      std::vector<lumistage::AravisCameraConfig> configs(rig.cameraCount());  // others' stay empty
      for (size_t k = 0; k < node.cameras.size(); ++k) {
        lumistage::AravisCameraConfig& config = configs[node.cameras[k]];
        config.device = devices.empty()
                            ? lumistage::VirtualGigeCameras::addressOf(address, node.cameras[k])
                            : devices[k];
        config.pixel_format = *format;
        config.frame_rate_hz = fps;
      }
      source = std::make_unique<lumistage::AravisSource>(rig, configs);
    } else {
      throw std::runtime_error(
          "give the node's cameras: --session DIR, or --address / --device for Aravis cameras");
    }
    lumistage::NodeEndpointConfig endpoint;
    endpoint.connect = studio;
    endpoint.name = node.name;
    if (plain) {
      endpoint.security = lumistage::TransportSecurity::kPlain;
    } else {
      if (keys.empty())
        throw std::runtime_error("give --keys DIR (or --plain on a closed network)");
      const lumistage::KeyStore store(keys);
      endpoint.node_key = store.nodeKey(node.name);
      endpoint.studio_public_key = store.studioPublicKey();
    }
    lumistage::CameraNode camera_node(rig, node.name, std::move(source), endpoint,
                                      lumistage::loadBody(body), node_options);
    // SIGINT, SIGTERM or SIGHUP: the node closes its take and stops (a second one ends it at once).
    std::atomic<bool>& stop = lumistage::stopOnSignals();
    fmt::print("node {}: {} cameras, serving {}\n", node.name, node.cameras.size(), studio);
    if (!takes.empty()) {
      // For the log (journalctl): where takes go, and the room there (the studio shows it too).
      const lumistage::DiskSpace disk = lumistage::diskSpaceAt(takes);
      fmt::print("node {}: takes go to {}{}\n", node.name, takes,
                 disk.free_bytes >= 0 ? " (" + lumistage::bytesInWords(disk.free_bytes) + " free)"
                                      : std::string(" (its free space unknown)"));
    }
    std::fflush(stdout);
    // Whether the node stopped on its own (its source ended or failed), not as asked: a failure,
    // for `lumistage run` and systemd to see.
    std::atomic<bool> stopped_alone{false};
    if (monitor) {
      // The node works on its own threads; the window lives on this one (GLFW wants the main
      // thread). Closing the window stops the node.
      std::thread worker([&camera_node, &stop, &stopped_alone] {
        camera_node.run(stop);
        if (!stop.exchange(true)) stopped_alone = true;  // closes the window too
      });
      bool monitor_failed = false;
      try {
        lumistage::runNodeMonitor(camera_node, rig, node.name, stop, monitor_screenshot);
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
  } catch (const std::exception& e) {
    fmt::print(stderr, "lumistage-node: error: {}\n", e.what());
    return 1;
  }
}
