#include "app/cli/camera_commands.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <thread>

#include "app/cli/checks.h"
#include "app/cli/progress.h"
#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/base/stop_signal.h"
#include "core/capture/aravis_source.h"
#include "core/capture/frame_grouper.h"
#include "core/capture/session_reader.h"
#include "core/capture/session_recorder.h"
#include "core/capture/session_source.h"
#include "core/capture/virtual_gige_cameras.h"
#include "core/geometry/rig_file.h"
#include "core/sim/virtual_studio.h"

namespace lumistage {

namespace {

// The virtual cameras hold every frame they loop in memory: a loop that would take more than half
// of this machine's memory is refused before anything is loaded or rendered, naming how many
// frames would fit.
void checkLoopFits(const Rig& rig, PixelFormat format, int frames) {
  const size_t set_bytes = size_t(rig.pixelsPerSet()) * bytesPerPixel(format);
  double memory = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  // In a container, its memory limit (cgroup v2) when lower.
  if (std::ifstream limit("/sys/fs/cgroup/memory.max"); limit) {
    double bytes = 0;
    if (limit >> bytes && bytes > 0) memory = std::min(memory, bytes);
  }
  const double limit = memory / 2, needed = double(set_bytes) * frames;
  if (memory <= 0 || needed <= limit) return;
  throw Error(fmt::format(
      "--frames {}: {} frames of {} cameras need {:.0f} MiB, over half this machine's memory "
      "({:.0f} MiB); at most --frames {} fit",
      frames, frames, rig.cameraCount(), needed / 1048576.0, limit / 1048576.0,
      int(limit / double(std::max<size_t>(1, set_bytes)))));
}

double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

PixelFormat pixelFormatOption(const std::string& name) {
  const std::optional<PixelFormat> format = parsePixelFormat(name);
  if (!format)
    throw CLI::ValidationError("--pixel-format",
                               "expected one of " + pixelFormatNames() + ", got '" + name + "'");
  return *format;
}

void addCamerasCommand(CLI::App& app) {
  CLI::App* cameras =
      app.add_subcommand("cameras", "List the GigE Vision and USB3 Vision cameras Aravis finds");
  cameras->callback([] {
    const std::vector<AravisDeviceInfo> devices = discoverAravisCameras();
    if (devices.empty()) {
      fmt::print(
          "no cameras found (GigE Vision discovery does not reach loopback: open virtual cameras "
          "by "
          "address)\n");
    }
    for (const AravisDeviceInfo& d : devices) {
      fmt::print("{:<28} {:<12} {:<16} serial {:<14} {}\n", d.id, d.protocol,
                 d.vendor + " " + d.model, d.serial, d.address);
    }
  });
}

struct VirtualArgs {
  std::string config, session, address = "127.0.1.1", pixel_format = "bayer_rggb8";
  int frames = 30;
  double seconds = 0;
};

// The frames to serve, loaded from --session or rendered from --config; `rig` and `format` become
// theirs.
std::shared_ptr<FrameLoop> virtualFrameLoop(const VirtualArgs& v, Rig& rig, PixelFormat& format) {
  auto loop = std::make_shared<FrameLoop>();
  if (!v.session.empty()) {
    // A recording, in its own pixel format, as the cameras would have delivered it.
    const SessionReader reader(v.session);  // which logs its warnings
    rig = reader.rig();
    format = reader.pixelFormat();
    loop->fps = reader.fps();
    loop->frames.resize(rig.cameraCount());
    const int count = std::min(v.frames, reader.frameCount());
    if (count == 0) throw Error(v.session + ": no complete frame to serve");
    checkLoopFits(rig, format, count);
    std::vector<CameraFrame> frames;
    for (int f = 0; f < count; ++f) {
      reader.readFrame(f, frames);
      for (int c = 0; c < rig.cameraCount(); ++c)
        loop->frames[c].push_back(std::move(frames[c].image));
      printProgress("load", f + 1, count);
    }
  } else {
    if (v.config.empty()) throw CLI::RequiredError("--config or --session");
    StudioConfig config = loadStudioConfig(v.config);
    rig = config.rig;
    checkLoopFits(rig, format, v.frames);
    VirtualStudio studio(std::move(config), v.frames);
    fmt::print("rendering {} frames of {} cameras on {}\n", v.frames, rig.cameraCount(),
               studio.rendererDescription());
    *loop = renderFrameLoop(studio, v.frames, format,
                            [](int done, int total) { printProgress("render", done, total); });
  }
  return loop;
}

void runVirtualCameras(const VirtualArgs& v) {
  PixelFormat format = pixelFormatOption(v.pixel_format);
  Rig rig;
  const std::shared_ptr<FrameLoop> loop = virtualFrameLoop(v, rig, format);
  VirtualGigeCameras server(rig, loop, format, v.address);
  for (int c = 0; c < rig.cameraCount(); ++c) {
    fmt::print("{} ({}x{}, {}, {} fps) at {}\n", rig.camera(c).name(), rig.camera(c).width(),
               rig.camera(c).height(), pixelFormatName(format), loop->fps, server.addresses()[c]);
  }
  fmt::print("serving; stop with Ctrl-C\n");
  std::fflush(stdout);
  const std::atomic<bool>& stop = stopOnSignals();
  const auto start = std::chrono::steady_clock::now();
  while (!stop && (v.seconds <= 0 || std::chrono::steady_clock::now() - start <
                                         std::chrono::duration<double>(v.seconds))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
}

void addVirtualCamerasCommand(CLI::App& app) {
  auto v = std::make_shared<VirtualArgs>();
  CLI::App* serve = app.add_subcommand(
      "virtual-cameras",
      "Serve the virtual studio through GigE Vision: camera i of the rig at ADDRESS+i");
  auto* config_option =
      serve->add_option("--config", v->config, "studio config (YAML): render its frames");
  auto* session_option =
      serve->add_option("--session", v->session, "or serve a recorded session's frames");
  config_option->excludes(session_option);
  serve->add_option("--frames", v->frames, "frames rendered and looped")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  serve->add_option("--address", v->address, "address of the first camera")->capture_default_str();
  serve->add_option("--pixel-format", v->pixel_format, pixelFormatNames())->capture_default_str();
  serve->add_option("--seconds", v->seconds, "stop after this long (default: until interrupted)")
      ->check(within(0.1, 1e7));
  serve->callback([v] { runVirtualCameras(*v); });
}

struct StreamArgs {
  std::string rig, address = "127.0.1.1", pixel_format = "bayer_rggb8", session, replay = "rate",
                   record, image_files = "pnm";
  std::vector<std::string> devices;
  double seconds = 5, fps = 25;
};

// The session replayed (`replayed` its reader), or the rig's Aravis cameras.
std::unique_ptr<FrameSource> openStreamSource(const StreamArgs& s, const SessionReader*& replayed) {
  if (!s.session.empty()) {
    ReplayOptions options;
    if (s.replay == "rate") {
      options.mode = ReplayMode::kRecordedRate;
    } else if (s.replay == "fast") {
      options.mode = ReplayMode::kAsFastAsPossible;
    } else if (s.replay == "memory") {
      options.mode = ReplayMode::kFromMemory;
    } else {
      throw CLI::ValidationError("--replay",
                                 "expected rate, fast or memory, got '" + s.replay + "'");
    }
    auto session = std::make_unique<SessionSource>(s.session, options);
    replayed = &session->reader();
    return session;
  }
  if (s.rig.empty()) throw CLI::RequiredError("--rig (or --session)");
  const Rig rig = loadRig(s.rig);
  if (!s.devices.empty() && s.devices.size() != static_cast<size_t>(rig.cameraCount())) {
    throw Error(fmt::format("--device given {} times for a rig of {} cameras", s.devices.size(),
                            rig.cameraCount()));
  }
  std::vector<AravisCameraConfig> configs(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    configs[c].device =
        s.devices.empty() ? VirtualGigeCameras::addressOf(s.address, c) : s.devices[c];
    configs[c].pixel_format = pixelFormatOption(s.pixel_format);
    configs[c].frame_rate_hz = s.fps;
  }
  return std::make_unique<AravisSource>(rig, configs);
}

// The recorder of --record, and how long the disk lasts.
std::unique_ptr<SessionRecorder> startRecording(const StreamArgs& s, const Rig& rig,
                                                const SessionReader* replayed) {
  // A replayed session is recorded in its own format and at its own rate.
  const PixelFormat format = replayed ? replayed->pixelFormat() : pixelFormatOption(s.pixel_format);
  const double fps = replayed ? replayed->fps() : s.fps;
  auto recorder = std::make_unique<SessionRecorder>(s.record, rig, format, fps,
                                                    s.session.empty() ? "aravis" : "replay", 8,
                                                    *parseImageFiles(s.image_files));
  // How long the disk lasts at the cameras' raw rate (PNM files are the raw bytes; PNG less).
  const double bytes_per_s = double(rig.pixelsPerSet()) * bytesPerPixel(format) * fps;
  if (const DiskSpace disk = diskSpaceAt(s.record); disk.free_bytes >= 0 && bytes_per_s > 0) {
    const double minutes = double(disk.free_bytes) / bytes_per_s / 60;
    fmt::print("recording to {}: {} free, about {:.0f} min at the cameras' {:.0f} MB/s{}\n",
               s.record, bytesInWords(disk.free_bytes), minutes, bytes_per_s / 1e6,
               minutes < 10 ? " (little room: the recording stops when the disk is full)" : "");
  }
  return recorder;
}

// Each camera's frames, rate, drops and resends, then the totals and the CPU they took.
void printStreamStats(FrameSource& source, double wall, double cpu, int64_t bytes) {
  const Rig& rig = source.rig();
  fmt::print("{:<8} {:>8} {:>8} {:>8} {:>8}  {}\n", "camera", "frames", "fps", "dropped", "resends",
             "last error");
  int64_t frames = 0;
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const CameraStats st = source.stats(c);
    frames += st.frames;
    fmt::print("{:<8} {:>8} {:>8.1f} {:>8} {:>8}  {}\n", rig.camera(c).name(), st.frames,
               st.frames / wall, st.dropped, st.resends, st.last_error);
  }
  fmt::print("{} frames in {:.1f} s ({:.1f} MB/s); CPU {:.0f}% of one core, {:.2f} ms per frame\n",
             frames, wall, bytes / wall / 1e6, 100 * cpu / wall,
             frames > 0 ? 1000 * cpu / frames : 0.0);
}

void runStream(const StreamArgs& s) {
  const SessionReader* replayed = nullptr;  // the session replayed, if any
  std::unique_ptr<FrameSource> source = openStreamSource(s, replayed);
  const Rig& rig = source->rig();
  // Recording takes complete sets of one instant: frames grouped by id.
  std::unique_ptr<SessionRecorder> recorder;
  std::unique_ptr<FrameGrouper> grouper;
  if (!s.record.empty()) {
    recorder = startRecording(s, rig, replayed);
    grouper = std::make_unique<FrameGrouper>(rig.cameraCount());
  }
  const double cpu_start = cpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  CameraFrame frame;
  FrameSet set;
  int64_t bytes = 0, incomplete = 0, first_timestamp = -1;
  // Ctrl-C, SIGTERM or SIGHUP ends the stream in order: the recording is finished and whole.
  const std::atomic<bool>& stop = stopOnSignals();
  while (!stop && !source->finished() &&
         std::chrono::steady_clock::now() - start < std::chrono::duration<double>(s.seconds)) {
    if (!source->next(frame, std::chrono::milliseconds(200))) continue;
    bytes += static_cast<int64_t>(frame.image.pixels.size());
    if (!grouper) continue;
    grouper->push(frame);
    while (grouper->pop(set)) {
      if (!set.complete()) {
        ++incomplete;
        continue;
      }
      if (first_timestamp < 0) first_timestamp = set.timestamp_ns;
      std::vector<Image> images;
      recorder->takeSpareImages(images);
      images.resize(set.frames.size());
      for (size_t c = 0; c < set.frames.size(); ++c) std::swap(images[c], set.frames[c].image);
      recorder->push(set.frame_id, set.timestamp_ns - first_timestamp, std::move(images));
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = cpuSeconds() - cpu_start;
  printStreamStats(*source, wall, cpu, bytes);
  if (recorder) {
    recorder->stop();
    const RecorderStats st = recorder->stats();
    fmt::print(
        "recorded {} frame sets to {} ({:.1f} MB), {} dropped by the recorder, {} incomplete "
        "sets left out{}\n",
        st.written, s.record, st.bytes / 1e6, st.dropped, incomplete,
        st.failed ? "; recording stopped: " + st.last_error : "");
    if (st.failed) throw Error(st.last_error);
  }
  // A source that stopped on a failure (every frame left of a replay damaged) is not a stream
  // that ran its course.
  if (const std::string failure = source->failure(); !failure.empty()) throw Error(failure);
}

void addStreamCommand(CLI::App& app) {
  auto s = std::make_shared<StreamArgs>();
  CLI::App* stream = app.add_subcommand("stream",
                                        "Stream from Aravis cameras or a recorded session; report "
                                        "rate, drops and CPU; optionally record");
  stream->add_option("--rig", s->rig, "rig file: one Aravis camera per rig camera");
  stream->add_option("--address", s->address, "address of the first camera (camera i at ADDRESS+i)")
      ->capture_default_str();
  stream->add_option("--device", s->devices,
                     "camera devices in rig order (address, serial or id), instead of --address");
  stream->add_option("--pixel-format", s->pixel_format, pixelFormatNames())->capture_default_str();
  stream->add_option("--fps", s->fps, "frame rate asked of the cameras")
      ->check(within(0.1, 1000))
      ->capture_default_str();
  stream->add_option("--session", s->session, "replay this recorded session instead of cameras");
  stream->add_option("--replay", s->replay, "replay pace: rate (as recorded), fast, memory")
      ->capture_default_str();
  stream->add_option("--seconds", s->seconds, "how long")
      ->check(within(0.1, 1e7))
      ->capture_default_str();
  stream->add_option("--record", s->record,
                     "record complete frame sets into this new session folder");
  stream
      ->add_option("--image-files", s->image_files,
                   "how --record stores the images: pnm (raw pixels, keeps up with the cameras) "
                   "or png (about 30% smaller, 10 ms or more a 1024x768 image to encode)")
      ->check(CLI::IsMember({"pnm", "png"}))
      ->capture_default_str();
  stream->callback([s] { runStream(*s); });
}

}  // namespace

void addCameraCommands(CLI::App& app) {
  addCamerasCommand(app);
  addVirtualCamerasCommand(app);
  addStreamCommand(app);
}

}  // namespace lumistage
