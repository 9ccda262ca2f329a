#include "app/cli/run_command.h"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "app/cli/checks.h"
#include "app/cli/machine_info.h"
#include "app/cli/run_plot.h"
#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/base/stop_signal.h"
#include "core/live/video_feed.h"
#include "core/live/vmc_sender.h"
#include "core/pipeline/local_run.h"
#include "core/render/view_recorder.h"

namespace lumistage {

namespace {

namespace fs = std::filesystem;

// What the machine spent on the run, in cores (1.0: one core busy all the time).
struct CpuUse {
  double studio_cores = 0, nodes_cores = 0;
};

double processCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
}

// The whole system's CPU (the studio and every node) per frame shown, ms: a figure machine noise
// moves far less than the frame rate; -1 when no frame was shown.
double cpuMsPerFrame(const CpuUse& cpu, double fps) {
  return fps > 0 ? 1000.0 * (cpu.studio_cores + cpu.nodes_cores) / fps : -1.0;
}

// Text for a JSON string: quotes, backslashes and control characters made spaces.
std::string jsonSafe(const std::string& text) {
  std::string safe;
  for (char ch : text) safe += (ch == '"' || ch == '\\' || ch < ' ') ? ' ' : ch;
  return safe;
}

// The view's live feed in the report: null when there was none.
std::string feedJson(const VideoFeed* feed) {
  if (!feed) return "null";
  return fmt::format(
      "{{\"url\": \"{}\", \"frames_sent\": {}, \"frames_dropped\": {}, \"send_ms\": {:.3f}, "
      "\"connections\": {}, \"error\": \"{}\"}}",
      jsonSafe(feed->target().url), feed->framesSent(), feed->framesDropped(), feed->sendMs(),
      feed->connections(), jsonSafe(feed->status().error()));
}

std::string reportJson(const RunReport& r, const CpuUse& cpu, const std::string& machine,
                       const ViewData& view, int max_in_flight, const VideoFeed* feed) {
  std::string stages;
  for (const auto& [name, ms] : r.stage_ms)
    stages += fmt::format("{}\"{}\": {:.3f}", stages.empty() ? "" : ", ", name, ms);
  std::string parts;
  for (const auto& [name, ms] : r.latency_parts_ms)
    parts += fmt::format("{}\"{}\": {:.3f}", parts.empty() ? "" : ", ", name, ms);
  // Figures a node never gave (it sent nothing, or no frame of it was shown) are null.
  const auto measured = [](double v, int decimals) {
    return v < 0 ? std::string("null") : fmt::format("{:.{}f}", v, decimals);
  };
  std::string nodes;
  for (const NodeReport& n : r.nodes) {
    std::string cameras;
    for (const CameraHealth& c : n.cameras) {
      cameras += fmt::format(
          "{}{{\"camera\": \"{}\", \"frames\": {}, \"dropped\": {}, \"fps\": {:.2f}, "
          "\"last_error\": \"{}\", \"key\": \"{}\"}}",
          cameras.empty() ? "" : ", ", c.camera, c.frames, c.dropped, c.frame_rate_hz,
          jsonSafe(c.last_error), jsonSafe(c.key));
    }
    nodes += fmt::format(
        "{}\n    {{\"name\": \"{}\", \"lost\": {}, \"messages\": {}, \"bytes\": {}, "
        "\"bytes_per_frame\": {}, \"frames_missed\": {}, "
        "\"times_lost\": {}, \"bad_messages\": {}, \"statistics_ms\": {}, "
        "\"image_ms\": {}, \"cameras\": [{}]}}",
        nodes.empty() ? "" : ",", n.name, n.lost ? "true" : "false", n.messages, n.bytes,
        measured(n.bytes_per_frame, 0), n.frames_missed, n.times_lost, n.bad_messages,
        measured(n.statistics_ms, 2), measured(n.image_ms, 2), cameras);
  }
  return fmt::format(
      "{{\n  \"fps\": {:.3f},\n  \"latency_ms_p50\": {:.3f},\n  \"latency_ms_p95\": {:.3f},\n  "
      "\"stage_ms\": {{{}}},\n  \"latency_parts_ms\": {{{}}},\n"
      "  \"node_bytes_per_frame\": {:.1f},\n  \"raw_bytes_per_frame_per_node\": {:.1f},\n  "
      "\"node_bytes_per_s\": {:.0f},\n  \"frames\": {},\n"
      "  \"frames_dropped\": {},\n  \"frames_refused\": {},\n  \"frames_overtaken\": {},\n"
      "  \"frames_unshown\": {},\n  \"frames_held\": {},\n"
      "  \"frames_incomplete\": {},\n  \"max_frames_in_flight\": {},\n"
      "  \"statistics_deadline_ms\": {:.1f},\n  \"image_deadline_ms\": {:.1f},\n"
      "  \"deadlines_following\": {},\n"
      "  \"hull_agreement\": {:.4f},\n  \"frames_tracked\": {},\n  \"refusals\": {},\n"
      "  \"view\": \"{}x{}\",\n  \"cpu_cores_studio\": {:.3f},\n  \"cpu_cores_nodes\": {:.3f},\n"
      "  \"cpu_ms_per_frame\": {},\n  \"feed\": {},\n"
      "  \"machine\": {},\n  \"nodes\": [{}\n  ]\n}}\n",
      r.fps, r.latency_ms_p50, r.latency_ms_p95, stages, parts, r.node_bytes_per_frame,
      r.raw_bytes_per_frame_per_node, r.node_bytes_per_s, r.frames, r.frames_dropped,
      r.frames_refused, r.frames_overtaken, r.frames_unshown, r.frames_held, r.frames_incomplete,
      max_in_flight, r.statistics_deadline_ms, r.image_deadline_ms,
      r.deadlines_following ? "true" : "false", r.hull_agreement, r.frames_tracked, r.refusals,
      view.width, view.height, cpu.studio_cores, cpu.nodes_cores,
      measured(cpuMsPerFrame(cpu, r.fps), 2), feedJson(feed), machine, nodes);
}

// Once every node has told its takes' disk (true then): the disk that fills first, and a warning
// when it holds less than the run may still record (`seconds`), as the take stops there.
bool tellTakeDisk(const RunReport& r, double seconds) {
  for (const NodeReport& n : r.nodes) {
    if (!n.lost && n.take_seconds_left < 0) return false;
  }
  const NodeReport* fullest = fullestTakeDisk(r);
  if (!fullest) return false;
  fmt::print("take: the fullest node's disk ({}, {} free) holds {:.0f} min of takes{}\n",
             fullest->name, bytesInWords(fullest->take.free_bytes), fullest->take_seconds_left / 60,
             fullest->take_seconds_left < seconds
                 ? fmt::format("; less than the {:.0f} s this run may still record: the take "
                               "stops there when it fills",
                               seconds)
                 : "");
  std::fflush(stdout);
  return true;
}

// Stops the take, waits (at most 30 s) for every node to close its part, and says how each went.
// Returns the nodes whose part failed (stopped on an error: a full disk), or was never closed.
std::vector<std::string> finishTake(LocalPipelineRun& pipeline, const std::string& folder) {
  StudioCoordinator& studio = pipeline.studio();
  studio.stopTake();
  // The studio goes on past the frames asked for, until the nodes have closed the take.
  studio.setMaxFrames(0);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  auto finished = [&] {
    for (const NodeReport& n : studio.report().nodes) {
      if (!n.lost && !(n.take.take == studio.take().take && n.take.finished)) return false;
    }
    return true;
  };
  while (std::chrono::steady_clock::now() < end && pipeline.anyNodeRunning() && !finished())
    pipeline.runFor(std::chrono::milliseconds(100));
  const RecordData& take = studio.take();
  fmt::print("take {}: frames {} to {}\n", take.take, take.first_frame, take.last_frame);
  std::vector<std::string> failed;
  for (const NodeReport& n : studio.report().nodes) {
    const TakeStatusData& t = n.take;
    if (!t.error.empty() || !t.finished) failed.push_back(n.name);
    std::string disk;
    if (t.free_bytes >= 0) {
      disk = fmt::format("; its disk: {} free", bytesInWords(t.free_bytes));
      if (n.take_seconds_left >= 0)
        disk += fmt::format(", {:.0f} min of takes", n.take_seconds_left / 60);
    }
    fmt::print("  node {:<8} {} frame sets, {:.1f} MB, {} dropped{}{}{}\n", n.name, t.written,
               t.bytes / 1e6, t.dropped, t.finished ? "" : ", not closed",
               t.error.empty() ? "" : ", " + t.error, disk);
  }
  if (pipeline.nodesElsewhere()) {
    fmt::print(
        "each node wrote its part to its own TAKES/{}/<node>/: gather them into one folder "
        "and join them with lumistage session merge\n",
        take.take);
  } else {
    fmt::print("join the nodes' parts with: lumistage session merge {} --out {}-session\n", folder,
               folder);
  }
  return failed;
}

// The command line of `lumistage run`.
struct RunArgs {
  std::string session, json, keys, replay = "rate", rig, address, image, plot, view_size,
                                   record_view, record_take, listen, osc, feed;
  BodyChoice body;
  int nodes = 0, max_in_flight = StudioCoordinatorOptions{}.max_frames_in_flight, plate_frames = 0;
  int64_t frames = 150;
  double seconds = 60;
  bool plain = false;
};

// What the run's options say of where its inputs come from and its outputs go, checked before
// any node starts. Throws CLI::ValidationError or Error naming the option.
void checkRunArgs(const RunArgs& a) {
  if (!a.listen.empty()) {
    if (!a.session.empty() || !a.address.empty())
      throw CLI::ValidationError(
          "--listen",
          "the nodes on the stage's PCs bring their own cameras: no --session or "
          "--address with it");
    if (a.rig.empty()) throw CLI::ValidationError("--listen", "give --rig FILE");
  } else if (a.session.empty() == (a.rig.empty() || a.address.empty())) {
    throw CLI::ValidationError("--session",
                               "give either --session DIR, or --rig FILE with --address A");
  }
  // Nothing the run writes goes over, or into, the session it replays or the rig it reads.
  for (const auto& [option, path] : {std::pair<const char*, const std::string&>{"--json", a.json},
                                     {"--image", a.image},
                                     {"--plot", a.plot},
                                     {"--record-view", a.record_view},
                                     {"--record-take", a.record_take}}) {
    refuseOutputOverInputs(option, path, {{"--session", a.session}, {"--rig", a.rig}});
    // A take makes its own folder.
    if (std::string_view(option) != "--record-take") requireOutputFolder(option, path);
  }
  for (const auto& [option, path] :
       {std::pair<const char*, const std::string&>{"--image", a.image}, {"--plot", a.plot}}) {
    const std::string extension = lowercaseExtension(path);
    if (!path.empty() && extension != ".png" && extension != ".jpg" && extension != ".jpeg")
      throw Error(std::string(option) + " " + path + ": expected a .png or .jpg file");
  }
}

// Option `option`'s `text` as `parse` reads it (which throws Error for a text it cannot);
// none when the option was not given. Throws CLI::ValidationError naming the option.
template <typename Parse>
auto parsedOption(const char* option, const std::string& text, Parse parse)
    -> std::optional<decltype(parse(text))> {
  if (text.empty()) return std::nullopt;
  try {
    return parse(text);
  } catch (const Error& e) {
    throw CLI::ValidationError(option, e.what());
  }
}

// The view's size asked for (--view-size; 0 x 0: the default).
std::pair<int, int> viewSizeOf(const RunArgs& a) {
  // The view's size, checked before the nodes start: at most what a node's message may carry
  // (the nodes dropped every view message beyond it, and rendered nothing).
  int width = 0, height = 0;
  if (!a.view_size.empty()) {
    char x = 0;
    std::istringstream in(a.view_size);
    const int most = MessageLimits{}.max_image_pixels;
    if (!(in >> width >> x >> height) || x != 'x' || !(in >> std::ws).eof() || width < 16 ||
        height < 16 || width > 7680 || height > 4320 || int64_t(width) * height > most)
      throw CLI::ValidationError(
          "--view-size", fmt::format("expected WxH from 16x16 to 7680x4320 and at most {} pixels "
                                     "(4096x4096), e.g. 640x480, got {}",
                                     most, a.view_size));
  }
  return {width, height};
}

// The pipeline's options from the command line, the view `width` x `height` (0: the default);
// `take` the take's name (empty: none).
LocalRunOptions runOptions(const RunArgs& a, int width, int height, std::string& take) {
  LocalRunOptions options;
  options.session = a.session;
  options.rig = a.rig;
  options.address = a.address;
  options.replay = a.replay;
  options.nodes = a.nodes;
  options.plain = a.plain;
  options.keys = a.keys;
  options.listen = a.listen;
  if (a.plate_frames > 0 && !a.session.empty()) {
    throw CLI::ValidationError(
        "--plate-frames",
        "learns live cameras' plates; a session's is its plate/ folder, which "
        "its nodes key on by themselves (a replay starts at any of its frames)");
  }
  options.plate_frames = a.plate_frames;
  options.body = a.body;
  options.coordinator.max_frames = a.frames;
  if (!a.record_take.empty()) {
    const std::filesystem::path dir = std::filesystem::absolute(a.record_take);
    take = dir.filename().string();
    if (const Status named = checkTakeName(take); !named.ok())
      throw CLI::ValidationError("--record-take", named.error());
    options.takes = dir.parent_path();
  }
  options.coordinator.max_frames_in_flight = a.max_in_flight;
  // The one view this run renders bounds what a node may send the studio, and so what a
  // connection to its port may make it buffer.
  options.coordinator.max_view_pixels = a.view_size.empty() ? 320 * 240 : int64_t(width) * height;
  return options;
}

// The studio's view resized to `width` x `height`, with the same field of view.
void sizeView(StudioCoordinator& studio, int width, int height) {
  ViewData view = studio.view();
  const float scale = float(width) / view.width;
  view.fx *= scale;
  view.fy *= float(height) / view.height;
  view.cx = view.cx * scale;
  view.cy = view.cy * float(height) / view.height;
  view.width = width;
  view.height = height;
  studio.setView(view);
}

// The live outputs asked for (the skeleton over OSC, the view as a feed) and the view's
// recording, started.
void startOutputs(LocalPipelineRun& pipeline, const RunArgs& a, const std::optional<OscTarget>& osc,
                  const std::optional<FeedTarget>& feed) {
  if (osc) {
    pipeline.streamSkeleton(*osc);
    fmt::print("streaming the skeleton to {} (VMC over OSC)\n", osc->text());
  }
  if (feed) {
    pipeline.feedView(*feed, [](const std::string& error) {
      fmt::print(stderr, "lumistage run: {}; the run goes on\n", error);
    });
    fmt::print("feeding the view to {} ({}, {}x{}){}\n", feed->url, feed->carries(),
               pipeline.viewFeed()->width(), pipeline.viewFeed()->height(),
               feed->listener ? "; waiting for a receiver to call" : "");
  }
  if (!a.record_view.empty()) {
    pipeline.recordView(a.record_view, [](const std::string& error) {
      fmt::print(stderr, "lumistage run: recording stopped: {}\n", error);
    });
    if (const std::string notice = pipeline.viewRecording()->leftoverNotice(); !notice.empty())
      fmt::print("lumistage run: {}\n", notice);
  }
}

// What the machine spent on a run: its cores from the first frame done, over wall_s seconds.
struct RunUse {
  CpuUse cpu;
  double wall_s = 0;
};

// Runs the pipeline until --frames, --seconds, a signal (`stop`) or the last node's exit, starting
// the take (`take`: its name, or none) at the first frame done; says where the studio is, each
// node that exits and a signal that stopped it.
RunUse runPipeline(LocalPipelineRun& pipeline, const RunArgs& a, const std::string& take,
                   const std::atomic<bool>& stop) {
  StudioCoordinator& studio = pipeline.studio();
  // CPU use is measured from the first frame done: the nodes' start-up (loading a session into
  // memory, compiling shaders) is not the pipeline's load.
  double cpu_start = processCpuSeconds(), nodes_cpu_start = 0;
  auto wall_start = std::chrono::steady_clock::now();
  bool measuring = false;
  double nodes_cpu = 0;
  if (pipeline.nodesElsewhere()) {
    fmt::print("studio at {} ({}), waiting for the rig's {} nodes\n", studio.endpoint(),
               a.plain ? "plain" : "CURVE", pipeline.nodeNames().size());
  } else {
    fmt::print("studio at {} ({}), starting {} nodes\n", studio.endpoint(),
               a.plain ? "plain" : "CURVE", pipeline.nodeNames().size());
  }
  // Run in slices, watching the clock and the node processes: a node that exits (bad session,
  // wrong key file...) is reported; when none is left, or a signal asks (above), stop.
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(a.seconds);
  bool disk_told = take.empty();  // a take's disks: said once every node has told its own
  while (!stop && std::chrono::steady_clock::now() < end && pipeline.anyNodeRunning() &&
         (a.frames <= 0 || studio.framesDone() < a.frames)) {
    pipeline.runFor(std::chrono::milliseconds(100));
    if (!disk_told && measuring) {
      // What the run may still record: to --seconds, or --frames at the cameras' rate.
      const double fps = pipeline.reportedFrameRate().value_or(pipeline.frameRate());
      const double left_s =
          std::min(std::chrono::duration<double>(end - std::chrono::steady_clock::now()).count(),
                   fps > 0 ? double(a.frames - studio.framesDone()) / fps : a.seconds);
      disk_told = tellTakeDisk(studio.report(), left_s);
    }
    nodes_cpu = std::max(nodes_cpu, pipeline.nodeCpuSeconds());
    if (!measuring && studio.framesDone() > 0) {
      measuring = true;
      if (!take.empty()) {
        if (const Status started = studio.startTake(take); !started.ok())
          throw Error(started.error());
      }
      cpu_start = processCpuSeconds();
      nodes_cpu_start = nodes_cpu;
      wall_start = std::chrono::steady_clock::now();
    }
    for (const std::string& exit : pipeline.takeExits()) {
      fmt::print(stderr, "lumistage run: {}; see its message above\n", exit);
    }
  }
  if (stop) {
    fmt::print("lumistage run: stopped by {} after {} frames; closing (again to quit at once)\n",
               stopSignalName(stopSignal()), studio.framesDone());
    std::fflush(stdout);
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return {{(processCpuSeconds() - cpu_start) / wall_s, (nodes_cpu - nodes_cpu_start) / wall_s},
          wall_s};
}

// The view's recording and feed stopped, and how they went said; `view_feed` the feed stopped
// (none: there was none). Returns whether the recording failed.
bool stopOutputs(LocalPipelineRun& pipeline, std::unique_ptr<VideoFeed>& view_feed) {
  bool recording_failed = pipeline.viewRecordingFailed();  // stopped by a failure (a full disk)
  if (std::unique_ptr<ViewRecorder> recorder = pipeline.stopRecordingView()) {
    if (const Status recorded = recorder->status(); !recorded.ok()) {
      fmt::print(stderr, "lumistage run: recording of the view failed: {}\n", recorded.error());
      recording_failed = true;
    } else {
      fmt::print("recorded the view to {}: {} frames of {}x{} at {:g} fps\n",
                 recorder->file().string(), recorder->framesWritten(), recorder->width(),
                 recorder->height(), recorder->fps());
    }
  }
  view_feed = pipeline.stopFeedingView();
  if (view_feed) {
    const Status fed = view_feed->status();
    fmt::print(
        "view fed to {}: {} frames sent, {} dropped, {:.1f} ms a frame to encode and send{}\n",
        view_feed->target().url, view_feed->framesSent(), view_feed->framesDropped(),
        view_feed->sendMs(), fed.ok() ? "" : "; " + fed.error());
  }
  return recording_failed;
}

// The run's figures, as `lumistage run` prints them.
void printRunReport(const RunReport& r, const RunUse& use, LocalPipelineRun& pipeline) {
  fmt::print(
      "{} frames in all ({} dropped: {} at admission, {} overtaken by newer frames, {} without "
      "a node's image, {} of these held back for one; {} shown without one), {:.1f} frames a "
      "second; latency {:.1f} ms (median), {:.1f} ms (95%)\n",
      r.frames, r.frames_dropped, r.frames_refused, r.frames_overtaken, r.frames_unshown,
      r.frames_held, r.frames_incomplete, r.fps, r.latency_ms_p50, r.latency_ms_p95);
  fmt::print(
      "motion capture: {} of the {} frames tracked; {:.3f} of the posed body inside the "
      "silhouettes\n",
      r.frames_tracked, r.frames, r.hull_agreement);
  for (const auto& [stage, ms] : r.stage_ms) fmt::print("  {:<16} {:8.3f} ms\n", stage, ms);
  std::string parts;
  for (const auto& [part, ms] : r.latency_parts_ms)
    parts += fmt::format("{}{} {:.1f}", parts.empty() ? "" : ", ", part, ms);
  if (!parts.empty()) fmt::print("where a frame's latency went (ms, mean): {}\n", parts);
  fmt::print("deadlines now: statistics {:.0f} ms, images {:.0f} ms{}\n", r.statistics_deadline_ms,
             r.image_deadline_ms,
             r.deadlines_following ? " (stretched to a late node's answers)" : "");
  fmt::print(
      "bytes per frame per node {:.0f} against {:.0f} raw ({:.4f}), {:.1f} MB/s a node; {} "
      "refusals\n",
      r.node_bytes_per_frame, r.raw_bytes_per_frame_per_node,
      r.raw_bytes_per_frame_per_node > 0 ? r.node_bytes_per_frame / r.raw_bytes_per_frame_per_node
                                         : 0.0,
      r.node_bytes_per_s / 1e6, r.refusals);
  fmt::print(
      "CPU: the studio {:.2f} cores, the nodes {:.2f} cores (over {:.1f} s): {:.1f} ms a shown "
      "frame\n",
      use.cpu.studio_cores, use.cpu.nodes_cores, use.wall_s, cpuMsPerFrame(use.cpu, r.fps));
  for (const NodeReport& n : r.nodes) {
    const std::string answers =
        n.statistics_ms < 0 || n.image_ms < 0
            ? std::string(n.messages == 0 ? "never heard from" : "no answer measured")
            : fmt::format("answers in {:.1f} ms (statistics) and {:.1f} ms (image)",
                          n.statistics_ms, n.image_ms);
    fmt::print(
        "  node {:<8} {:<9} {} messages, missed {} frames, lost {} times, {} bad messages; {}\n",
        n.name, n.lost ? "lost" : "streaming", n.messages, n.frames_missed, n.times_lost,
        n.bad_messages, answers);
    for (const CameraHealth& c : n.cameras) {
      // The key said where it is not the green screen (a stage filmed without one).
      const bool masks = c.key == kKeyedFromMasks;
      fmt::print("      {:<8} {:6.1f} fps, {} frames, {} dropped{}{}\n", c.camera, c.frame_rate_hz,
                 c.frames, c.dropped, masks ? ", " + c.key : "",
                 c.last_error.empty() ? "" : ", " + c.last_error);
    }
  }
  if (const VmcSender* sender = pipeline.skeletonStream()) {
    fmt::print("skeleton to {}: {} bundles sent, {} lost\n", sender->target().text(),
               sender->bundlesSent(), sender->bundlesLost());
  }
}

// The files asked for: the figures as JSON (--json), the latency plot (--plot), the last view
// (--image).
void writeRunFiles(const RunArgs& a, const RunReport& r, const CpuUse& cpu,
                   LocalPipelineRun& pipeline, const VideoFeed* feed) {
  StudioCoordinator& studio = pipeline.studio();
  if (!a.json.empty() || !a.plot.empty()) {
    const MachineInfo machine = describeMachine();
    if (!a.json.empty())
      writeFileAtomically(
          a.json, reportJson(r, cpu, machineJson(machine), studio.view(), a.max_in_flight, feed));
    if (!a.plot.empty()) {
      const std::string source = a.session.empty() ? "Aravis cameras" : a.session;
      writeRunPlot(r,
                   fmt::format("{}, {} nodes, view {}x{}; {}, {} threads; OpenGL {}", source,
                               pipeline.nodeNames().size(), studio.view().width,
                               studio.view().height, machine.cpu, machine.cores, machine.opengl),
                   a.plot);
      fmt::print("wrote {}\n", a.plot);
    }
  }
  if (!a.image.empty()) {
    const BlendedImage& image = studio.lastImage();
    if (image.rgba.empty())
      throw Error("no blended view to write: no frame had the nodes' partial images");
    cv::Mat rgba(image.height, image.width, CV_8UC4, const_cast<uint8_t*>(image.rgba.data())),
        straight, bgra;
    // The view is premultiplied (its feathered silhouette); a PNG's alpha is not.
    cv::cvtColor(rgba, straight, cv::COLOR_mRGBA2RGBA);
    cv::cvtColor(straight, bgra, cv::COLOR_RGBA2BGRA);
    if (!cv::imwrite(a.image, bgra)) throw Error(a.image + ": cannot write the image");
    fmt::print("wrote {} (frame {})\n", a.image, image.frame_id);
  }
}

// The figures are printed either way, but a run a node died in did not measure the rig, and one
// whose recording failed did not do what it was asked: thrown.
void throwIfRunFailed(LocalPipelineRun& pipeline, bool recording_failed,
                      const std::vector<std::string>& take_failed) {
  if (pipeline.nodesFailed() > 0) {
    throw Error(fmt::format("{} node process{} failed during the run (see above)",
                            pipeline.nodesFailed(), pipeline.nodesFailed() > 1 ? "es" : ""));
  }
  if (recording_failed) throw Error("the view's recording failed (see above)");
  if (!take_failed.empty()) {
    std::string names;
    for (const std::string& n : take_failed) names += (names.empty() ? "" : ", ") + n;
    throw Error(fmt::format("the take lost the recording of node{} {} (see above)",
                            take_failed.size() > 1 ? "s" : "", names));
  }
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto a = std::make_shared<RunArgs>();
  CLI::App* run = app.add_subcommand("run",
                                     "Run the distributed pipeline on this machine: a node process "
                                     "per rig node, the studio's modules here");
  run->add_option("--session", a->session, "recorded session the nodes replay");
  run->add_option("--rig", a->rig, "or live Aravis cameras: the rig...");
  run->add_option("--address", a->address,
                  "...and its first camera's address (camera i at ADDRESS+i)");
  run->add_option("--listen", a->listen,
                  "or nodes on the stage's PCs: listen for them here (e.g. tcp://*:5570), with "
                  "--rig and --keys; no node process is started on this machine");
  run->add_option("--nodes", a->nodes, "how many of the rig's nodes to start (default: all)")
      ->check(within(1, 1000));
  run->add_option("--frames", a->frames, "stop after this many complete frames")
      ->check(within(1, 1e12))
      ->capture_default_str();
  run->add_option("--seconds", a->seconds, "or after this long")
      ->check(within(0.1, 1e7))
      ->capture_default_str();
  run->add_option("--max-in-flight", a->max_in_flight,
                  "frames between motion capture and done at once; a newer frame is dropped "
                  "before any work (0: no limit, frames queue)")
      ->capture_default_str();
  run->add_option("--replay", a->replay,
                  "node pace: rate (as recorded) or memory (decoded up front, as fast as possible)")
      ->capture_default_str();
  run->add_option("--keys", a->keys,
                  "key store (lumistage keys init); default: fresh keys in a temporary folder");
  addBodyOption(*run, a->body);
  run->add_flag("--plain", a->plain, "no CURVE encryption and authentication");
  run->add_option("--json", a->json, "write the figures as JSON");
  run->add_option("--plot", a->plot,
                  "write a PNG plot of every frame's latency and the frame rate over time");
  run->add_option("--view-size", a->view_size,
                  "the virtual view's size, WxH (default 320x240), the same field of view");
  run->add_option("--image", a->image,
                  "write the last blended view as PNG (the pipeline's output)");
  run->add_option("--record-view", a->record_view,
                  "record every blended view to this video at the cameras' rate (.mp4: H.264; "
                  ".avi: Motion-JPEG)");
  run->add_option("--plate-frames", a->plate_frames,
                  "a stage without a green screen: the nodes learn each camera's clean plate from "
                  "its first N frames, which must film the empty stage (the actor walks in after)")
      ->check(CLI::Range(0, 10000));
  run->add_option("--record-take", a->record_take,
                  "record the cameras' frames as a take: each node writes its cameras to "
                  "DIR/<node>/ from the first frame done to the end (lumistage session merge "
                  "DIR joins them)");
  run->add_option("--osc", a->osc,
                  "stream the tracked skeleton of every frame shown to HOST:PORT over OSC in the "
                  "VMC protocol (VSeeFace, EVMC4U for Unity, VMC4UE for Unreal, Blender; their "
                  "usual port is 39539)");
  run->add_option("--feed", a->feed,
                  "send the view live as H.264 in MPEG-TS to this URL, for OBS, vMix, ffplay or a "
                  "vision mixer: udp://HOST:PORT, srt://HOST:PORT (calling a receiver that "
                  "listens) or srt://:PORT?mode=listener (the receiver calls); or uncompressed "
                  "to a v4l2loopback device, v4l2:///dev/videoN, which OBS and browsers see as "
                  "a webcam");
  run->callback([a] {
    // Ctrl-C (or SIGTERM, SIGHUP) stops the run as its end would: the take closed, the view's
    // recording finished, the figures told, the nodes stopped and the run's key store removed.
    // Caught from the start: one that comes while the nodes start still stops them in order.
    const std::atomic<bool>& stop = stopOnSignals();
    checkRunArgs(*a);
    const auto osc = parsedOption("--osc", a->osc, parseOscTarget);
    const auto feed = parsedOption("--feed", a->feed, parseFeedUrl);
    const auto [width, height] = viewSizeOf(*a);
    std::string take;
    LocalPipelineRun pipeline(runOptions(*a, width, height, take));
    StudioCoordinator& studio = pipeline.studio();
    if (width > 0) sizeView(studio, width, height);
    startOutputs(pipeline, *a, osc, feed);
    const RunUse use = runPipeline(pipeline, *a, take, stop);
    // The figures are of the frames asked for (--frames, --seconds), before the pipeline goes on
    // while the nodes close a take.
    const RunReport r = studio.report();
    std::vector<std::string> take_failed;  // nodes whose part of the take was lost
    if (!take.empty() && !studio.take().take.empty())
      take_failed = finishTake(pipeline, a->record_take);
    std::unique_ptr<VideoFeed> view_feed;
    const bool recording_failed = stopOutputs(pipeline, view_feed);
    printRunReport(r, use, pipeline);
    writeRunFiles(*a, r, use.cpu, pipeline, view_feed.get());
    throwIfRunFailed(pipeline, recording_failed, take_failed);
  });
}

}  // namespace lumistage
