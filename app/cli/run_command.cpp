#include "app/cli/run_command.h"

#include <fmt/format.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/body/human_skeleton.h"
#include "core/capture/session_reader.h"
#include "core/geometry/rig_file.h"
#include "core/net/curve_keys.h"
#include "core/pipeline/studio_coordinator.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

std::string reportJson(const RunReport& r) {
  std::string stages;
  for (const auto& [name, ms] : r.stage_ms)
    stages += fmt::format("{}\"{}\": {:.3f}", stages.empty() ? "" : ", ", name, ms);
  std::string nodes;
  for (const NodeReport& n : r.nodes) {
    std::string cameras;
    for (const CameraHealth& c : n.cameras) {
      std::string error;
      for (char ch : c.last_error)
        error += (ch == '"' || ch == '\\' || ch < ' ') ? ' ' : ch;  // JSON-safe
      cameras += fmt::format(
          "{}{{\"camera\": \"{}\", \"frames\": {}, \"dropped\": {}, \"fps\": {:.2f}, "
          "\"last_error\": \"{}\"}}",
          cameras.empty() ? "" : ", ", c.camera, c.frames, c.dropped, c.frame_rate_hz, error);
    }
    nodes += fmt::format(
        "{}\n    {{\"name\": \"{}\", \"lost\": {}, \"messages\": {}, \"bytes\": {}, "
        "\"frames_missed\": {}, "
        "\"times_lost\": {}, \"bad_messages\": {}, \"cameras\": [{}]}}",
        nodes.empty() ? "" : ",", n.name, n.lost ? "true" : "false", n.messages, n.bytes,
        n.frames_missed, n.times_lost, n.bad_messages, cameras);
  }
  return fmt::format(
      "{{\n  \"fps\": {:.3f},\n  \"latency_ms_p50\": {:.3f},\n  \"latency_ms_p95\": {:.3f},\n  "
      "\"stage_ms\": {{{}}},\n"
      "  \"node_bytes_per_frame\": {:.1f},\n  \"raw_bytes_per_frame_per_node\": {:.1f},\n  "
      "\"frames\": {},\n"
      "  \"frames_dropped\": {},\n  \"hull_agreement\": {:.4f},\n  \"refusals\": {},\n  \"nodes\": "
      "[{}\n  ]\n}}\n",
      r.fps, r.latency_ms_p50, r.latency_ms_p95, stages, r.node_bytes_per_frame,
      r.raw_bytes_per_frame_per_node, r.frames, r.frames_dropped, r.hull_agreement, r.refusals,
      nodes);
}

}  // namespace

void addRunCommand(CLI::App& app) {
  struct Args {
    std::string session, json, keys, replay = "rate", rig, address;
    int nodes = 0;
    int64_t frames = 150;
    double seconds = 60;
    bool plain = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* run = app.add_subcommand("run",
                                     "Run the distributed pipeline on this machine: a node process "
                                     "per rig node, the studio's modules here");
  run->add_option("--session", a->session, "recorded session the nodes replay");
  run->add_option("--rig", a->rig, "or live Aravis cameras: the rig...");
  run->add_option("--address", a->address,
                  "...and its first camera's address (camera i at ADDRESS+i)");
  run->add_option("--nodes", a->nodes, "how many of the rig's nodes to start (default: all)");
  run->add_option("--frames", a->frames, "stop after this many complete frames")
      ->capture_default_str();
  run->add_option("--seconds", a->seconds, "or after this long")->capture_default_str();
  run->add_option("--replay", a->replay,
                  "node pace: rate (as recorded) or memory (decoded up front, as fast as possible)")
      ->capture_default_str();
  run->add_option("--keys", a->keys,
                  "key store (lumistage keys init); default: fresh keys in a temporary folder");
  run->add_flag("--plain", a->plain, "no CURVE encryption and authentication");
  run->add_option("--json", a->json, "write the figures as JSON");
  run->callback([a] {
    if (a->session.empty() == (a->rig.empty() || a->address.empty())) {
      throw CLI::ValidationError("--session",
                                 "give either --session DIR, or --rig FILE with --address A");
    }
    std::optional<SessionReader> reader;
    if (!a->session.empty()) reader.emplace(a->session);
    const Rig rig = reader ? reader->rig() : loadRig(a->rig);
    const int raw_bytes_per_pixel =
        reader ? bytesPerPixel(reader->pixelFormat()) : 1;  // live: Bayer
    const int node_count = a->nodes > 0 ? std::min(a->nodes, rig.nodeCount()) : rig.nodeCount();
    std::vector<std::string> names;
    for (int n = 0; n < node_count; ++n) names.push_back(rig.nodes()[n].name);

    StudioEndpointConfig endpoint;
    endpoint.bind = "tcp://127.0.0.1:*";
    fs::path keys = a->keys;
    const bool temporary_keys = keys.empty() && !a->plain;
    if (a->plain) {
      endpoint.security = TransportSecurity::kPlain;
    } else {
      if (temporary_keys) {
        keys = fs::temp_directory_path() / fmt::format("lumistage_run_keys_{}", ::getpid());
        KeyStore(keys).init(names, true);
      }
      const KeyStore store(keys);
      endpoint.studio_key = store.studioKey();
      endpoint.authorized = store.authorizedNodes();
    }
    StudioCoordinatorOptions options;
    options.max_frames = a->frames;
    options.raw_bytes_per_pixel = raw_bytes_per_pixel;
    StudioCoordinator studio(rig, endpoint, kHumanJointCount, options);
    fmt::print("studio at {} ({}), starting {} nodes\n", studio.endpoint(),
               a->plain ? "plain" : "CURVE", node_count);

    const std::string node_binary =
        (fs::read_symlink("/proc/self/exe").parent_path() / "lumistage-node").string();
    std::vector<pid_t> children;
    for (const std::string& name : names) {
      const pid_t pid = fork();
      if (pid < 0) throw Error("cannot start a node process");
      if (pid == 0) {
        std::vector<std::string> args = {node_binary, "--node", name, "--studio",
                                         studio.endpoint()};
        if (a->session.empty()) {
          args.insert(args.end(), {"--rig", a->rig, "--address", a->address});
        } else {
          args.insert(args.end(), {"--session", a->session, "--replay", a->replay});
        }
        if (a->plain) {
          args.push_back("--plain");
        } else {
          args.push_back("--keys");
          args.push_back(keys.string());
        }
        std::vector<char*> argv;
        for (std::string& s : args) argv.push_back(s.data());
        argv.push_back(nullptr);
        execv(node_binary.c_str(), argv.data());
        _exit(127);
      }
      children.push_back(pid);
    }
    // Run the studio in slices, watching the clock and the node processes: a node that exits
    // (bad session, wrong key file...) is reported with its status; when none is left, stop.
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(a->seconds);
    std::vector<bool> running(children.size(), true);
    int exited = 0;
    while (std::chrono::steady_clock::now() < end && exited < static_cast<int>(children.size()) &&
           (a->frames <= 0 || studio.framesDone() < a->frames)) {
      studio.runFor(std::chrono::milliseconds(100));
      for (size_t n = 0; n < children.size(); ++n) {
        int status = 0;
        if (running[n] && waitpid(children[n], &status, WNOHANG) == children[n]) {
          running[n] = false;
          ++exited;
          fmt::print(stderr, "lumistage run: node {} exited ({}); see its message above\n",
                     names[n],
                     WIFEXITED(status) ? fmt::format("status {}", WEXITSTATUS(status))
                                       : fmt::format("signal {}", WTERMSIG(status)));
        }
      }
    }
    for (size_t n = 0; n < children.size(); ++n) {
      if (running[n]) kill(children[n], SIGTERM);
    }
    for (size_t n = 0; n < children.size(); ++n) {
      if (running[n]) waitpid(children[n], nullptr, 0);
    }
    if (temporary_keys) fs::remove_all(keys);

    const RunReport r = studio.report();
    fmt::print(
        "{} frames in all ({} dropped), {:.1f} frames a second; latency {:.1f} ms (median), {:.1f} "
        "ms (95%)\n",
        r.frames, r.frames_dropped, r.fps, r.latency_ms_p50, r.latency_ms_p95);
    for (const auto& [stage, ms] : r.stage_ms) fmt::print("  {:<16} {:8.3f} ms\n", stage, ms);
    fmt::print("bytes per frame per node {:.0f} against {:.0f} raw ({:.4f}); {} refusals\n",
               r.node_bytes_per_frame, r.raw_bytes_per_frame_per_node,
               r.raw_bytes_per_frame_per_node > 0
                   ? r.node_bytes_per_frame / r.raw_bytes_per_frame_per_node
                   : 0.0,
               r.refusals);
    for (const NodeReport& n : r.nodes) {
      fmt::print(
          "  node {:<8} {:<9} {} messages, missed {} frames, lost {} times, {} bad messages\n",
          n.name, n.lost ? "lost" : "streaming", n.messages, n.frames_missed, n.times_lost,
          n.bad_messages);
      for (const CameraHealth& c : n.cameras) {
        fmt::print("      {:<8} {:6.1f} fps, {} frames, {} dropped{}\n", c.camera, c.frame_rate_hz,
                   c.frames, c.dropped, c.last_error.empty() ? "" : ", " + c.last_error);
      }
    }
    if (!a->json.empty()) writeFileAtomically(a->json, reportJson(r));
  });
}

}  // namespace lumistage
