#include "core/capture/session_reader.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string_view>
#include <type_traits>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/status.h"
#include "core/base/yaml_reader.h"
#include "core/geometry/rig_file.h"

namespace lumistage {

namespace fs = std::filesystem;

namespace {

// Whole-field parse: "12x" or "" is not a number.
template <typename T>
bool parseNumber(std::string_view text, T& out) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  if (ec != std::errc() || end != text.data() + text.size()) return false;
  if constexpr (std::is_floating_point_v<T>) return std::isfinite(out);  // not "nan" nor "inf"
  return true;
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(line.substr(start, comma - start));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

// Complete lines of a file and what follows the last newline (a torn line, or empty).
struct Lines {
  std::vector<std::string_view> complete;
  std::string_view torn;
};

Lines splitLines(std::string_view text) {
  Lines lines;
  size_t start = 0;
  for (size_t nl = text.find('\n'); nl != std::string_view::npos; nl = text.find('\n', start)) {
    lines.complete.push_back(text.substr(start, nl - start));
    start = nl + 1;
  }
  lines.torn = text.substr(start);
  return lines;
}

// Opens a camera image for reading, only if it is a regular file: a FIFO in a camera's folder
// blocked fopen for ever, a device would be read without end. `file` is null when it fails.
Status openImage(const fs::path& path, std::FILE*& file) {
  file = nullptr;
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    return Status::failure(
        errno == ENOENT ? "is missing" : fmt::format("cannot be opened: {}", std::strerror(errno)));
  }
  struct stat st {};
  Status opened;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    opened = Status::failure("is not a regular file (a FIFO, a folder or a device?)");
  } else if ((file = ::fdopen(fd, "rb")) == nullptr) {
    opened = Status::failure(fmt::format("cannot be opened: {}", std::strerror(errno)));
  }
  if (file == nullptr) ::close(fd);
  return opened;
}

// Whether `path` names something other than a regular file (what openImage refuses), for a
// reader that opens it itself (OpenCV).
bool existsButIsNotARegularFile(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  return !ec && fs::exists(status) && !fs::is_regular_file(status);
}

uint32_t bigEndian32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}

// Cheap check of a frame's PNG without decoding it: the header says size and channels, and the
// file ends with the IEND chunk (a file cut short by a crash or a full disk does not). Fails
// saying what is wrong.
Status checkPng(const fs::path& path, int width, int height, int channels) {
  std::FILE* file = nullptr;
  if (Status opened = openImage(path, file); !opened.ok()) return opened;
  std::array<unsigned char, 26> header{};
  std::array<unsigned char, 12> tail{};
  const bool header_read = std::fread(header.data(), 1, header.size(), file) == header.size();
  const bool tail_read = header_read && std::fseek(file, -long(tail.size()), SEEK_END) == 0 &&
                         std::fread(tail.data(), 1, tail.size(), file) == tail.size();
  std::fclose(file);
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static constexpr unsigned char kIend[12] = {0,   0,   0,    0,    'I',  'E',
                                              'N', 'D', 0xae, 0x42, 0x60, 0x82};
  if (!header_read) return Status::failure("is truncated (shorter than a PNG header)");
  if (std::memcmp(header.data(), kSignature, 8) != 0 || std::memcmp(header.data() + 12, "IHDR", 4))
    return Status::failure("is not a PNG file");
  const int w = int(bigEndian32(header.data() + 16)), h = int(bigEndian32(header.data() + 20));
  if (w != width || h != height)
    return Status::failure(fmt::format("is a {}x{} image, expected {}x{}", w, h, width, height));
  const int depth = header[24], colour = header[25];
  const int expected_colour = channels == 3 ? 2 : 0;  // PNG colour types: 0 grey, 2 RGB
  if (depth != 8 || colour != expected_colour) {
    return Status::failure(fmt::format("has bit depth {} and PNG colour type {}, expected 8-bit {}",
                                       depth, colour,
                                       channels == 3 ? "RGB (type 2)" : "grey (type 0)"));
  }
  if (!tail_read || std::memcmp(tail.data(), kIend, sizeof kIend) != 0)
    return Status::failure("is truncated (it does not end with the PNG end chunk)");
  return {};
}

// A PNM camera image's header ("P5" or "P6", width, height, 255, each followed by one whitespace
// character; no comments, as the writer writes it) of the expected size and channels: its length
// into `length`.
Status parsePnmHeader(std::string_view data, int width, int height, int channels, size_t& length) {
  const std::string_view magic = channels == 3 ? "P6" : "P5";
  if (data.size() < 3 || (data.substr(0, 2) != "P5" && data.substr(0, 2) != "P6") ||
      !std::isspace(static_cast<unsigned char>(data[2]))) {
    return Status::failure(data.size() < 3 ? "is truncated (shorter than a PNM header)"
                                           : "is not a PNM file");
  }
  if (data.substr(0, 2) != magic) {
    return Status::failure(fmt::format("is a {} file, expected {} ({})", data.substr(0, 2), magic,
                                       channels == 3 ? "RGB" : "grey"));
  }
  size_t at = 3;
  int fields[3] = {0, 0, 0};
  for (int& field : fields) {
    const size_t end = data.find_first_of(" \t\r\n", at);
    if (end == std::string_view::npos || !parseNumber(data.substr(at, end - at), field)) {
      return Status::failure("has a malformed PNM header");
    }
    at = end + 1;
  }
  if (fields[0] != width || fields[1] != height) {
    return Status::failure(
        fmt::format("is a {}x{} image, expected {}x{}", fields[0], fields[1], width, height));
  }
  if (fields[2] != 255) {
    return Status::failure(fmt::format("has PNM maxval {}, expected 255 (8-bit)", fields[2]));
  }
  length = at;
  return {};
}

// Reads an open PNM file's header (parsePnmHeader) and leaves the file just after it.
Status readPnmHeader(std::FILE* file, int width, int height, int channels, size_t& length) {
  std::array<char, 64> header{};
  const size_t read = std::fread(header.data(), 1, header.size(), file);
  Status parsed =
      parsePnmHeader(std::string_view(header.data(), read), width, height, channels, length);
  if (!parsed.ok()) return parsed;
  if (std::fseek(file, long(length), SEEK_SET) == 0) return {};
  return Status::failure(fmt::format("cannot be read past its header: {}", std::strerror(errno)));
}

// Cheap check of a frame's PNM: its header, and a file as long as the header and every pixel (a
// file cut short by a crash or a full disk is not).
Status checkPnm(const fs::path& path, int width, int height, int channels) {
  std::FILE* file = nullptr;
  if (Status opened = openImage(path, file); !opened.ok()) return opened;
  size_t length = 0;
  Status header = readPnmHeader(file, width, height, channels, length);
  const long size = std::fseek(file, 0, SEEK_END) == 0 ? std::ftell(file) : -1;
  std::fclose(file);
  if (!header.ok()) return header;
  const long expected = long(length) + long(width) * height * channels;
  if (size != expected)
    return Status::failure(fmt::format("is {} bytes, expected {} (its header and {}x{} pixels){}",
                                       size, expected, width, height,
                                       size < expected ? ": truncated" : ""));
  return {};
}

// Reads a PNM camera image into `image` (the pixels straight into its buffer); fails saying what
// is wrong, naming the file.
Status readPnm(const fs::path& path, int64_t frame_id, const Camera& camera, PixelFormat format,
               Image& image) {
  const int channels = bytesPerPixel(format);
  std::FILE* file = nullptr;
  if (Status opened = openImage(path, file); !opened.ok())
    return Status::failure(
        fmt::format("{}: frame {}: {}", path.string(), frame_id, opened.error()));
  size_t length = 0;
  const Status header = readPnmHeader(file, camera.width(), camera.height(), channels, length);
  image.resize(format, camera.width(), camera.height());
  const bool whole =
      header.ok() &&
      std::fread(image.pixels.data(), 1, image.pixels.size(), file) == image.pixels.size() &&
      std::fgetc(file) == EOF;
  std::fclose(file);
  if (whole) return {};
  return Status::failure(fmt::format(
      "{}: frame {}: {} (damaged since the session was opened?)", path.string(), frame_id,
      !header.ok() ? header.error()
                   : fmt::format("is not a {}x{} {} image's header and pixels", camera.width(),
                                 camera.height(), pixelFormatName(format))));
}

// One camera image of the session's format and files (frame `id`, for the message) into `image`.
Status readImageFile(const fs::path& path, int64_t id, const Camera& camera, PixelFormat format,
                     ImageFiles files, Image& image) {
  if (files == ImageFiles::kPnm) return readPnm(path, id, camera, format, image);
  cv::Mat decoded;
  if (existsButIsNotARegularFile(path)) {
    return Status::failure(fmt::format(
        "{}: frame {}: is not a regular file (a FIFO, a folder or a device?)", path.string(), id));
  }
  try {
    decoded = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return Status::failure(path.string() + ": cannot decode: " + e.err);
  }
  const int type = format == PixelFormat::kRgb8 ? CV_8UC3 : CV_8UC1;
  if (decoded.empty() || decoded.type() != type || decoded.cols != camera.width() ||
      decoded.rows != camera.height()) {
    return Status::failure(fmt::format(
        "{}: frame {}: cannot decode a {}x{} {} image from it (damaged since the session "
        "was opened?)",
        path.string(), id, camera.width(), camera.height(), pixelFormatName(format)));
  }
  image.resize(format, camera.width(), camera.height());
  cv::Mat target(camera.height(), camera.width(), type, image.pixels.data());
  if (format == PixelFormat::kRgb8)
    cv::cvtColor(decoded, target, cv::COLOR_BGR2RGB);  // OpenCV decodes to BGR
  else
    decoded.copyTo(target);
  return {};
}

}  // namespace

SessionReader::SessionReader(const fs::path& folder) : folder_(folder) {
  std::error_code ec;
  if (!fs::is_directory(folder_, ec))
    throw Error(folder_.string() + ": not a session folder (no such folder)");
  readSessionYaml();
  readIndex();
  checkImages();
  // Every command that opens a session says why it is shorter than recorded.
  for (const std::string& warning : warnings_) spdlog::warn("{}", warning);
}

void SessionReader::readSessionYaml() {
  const fs::path path = folder_ / "session.yaml";
  const YamlReader yaml(path.string());
  const YAML::Node root = yaml.parseDocument(readFile(path));
  yaml.requireMap(root, "");
  // The format first: another kind of file's keys are not for the message.
  const YAML::Node format = yaml.required(root, "", "format", "lumistage-session");
  if (!format.IsScalar() || format.Scalar() != "lumistage-session") {
    yaml.fail(format, "format",
              "expected lumistage-session, got " +
                  (format.IsScalar() ? quotedInput(format.Scalar()) : std::string("no text")));
  }
  yaml.checkKeys(root, "",
                 {"format", "version", "source", "rig", "fps", "pixel_format", "image_files",
                  "cameras", "truth"});
  const YAML::Node version = yaml.required(root, "", "version", "1");
  if (yaml.integer(version, "version") != 1) {
    yaml.fail(version, "version",
              "this build reads version 1, got " + version.Scalar() + " (a newer Lumistage?)");
  }
  source_ = yaml.string(yaml.required(root, "", "source", "where the frames came from"), "source");
  const YAML::Node fps = yaml.required(root, "", "fps", "frames per second");
  fps_ = yaml.number(fps, "fps");
  if (!(fps_ > 0 && fps_ <= 1000))
    yaml.fail(fps, "fps", "expected a frame rate above 0 and at most 1000, got " + fps.Scalar());
  const YAML::Node pixel_format = yaml.required(root, "", "pixel_format", pixelFormatNames());
  const std::optional<PixelFormat> parsed =
      parsePixelFormat(yaml.string(pixel_format, "pixel_format"));
  if (!parsed) {
    yaml.fail(
        pixel_format, "pixel_format",
        "expected one of " + pixelFormatNames() + ", got " + quotedInput(pixel_format.Scalar()));
  }
  format_ = *parsed;
  const YAML::Node image_files = yaml.required(root, "", "image_files", "png or pnm");
  const std::optional<ImageFiles> files = parseImageFiles(yaml.string(image_files, "image_files"));
  if (!files) {
    yaml.fail(image_files, "image_files",
              "expected png or pnm, got " + quotedInput(image_files.Scalar()));
  }
  files_ = *files;
  const YAML::Node truth = yaml.required(root, "", "truth", "true or false");
  if (!truth.IsScalar() || !YAML::convert<bool>::decode(truth, truth_))
    yaml.fail(truth, "truth", "expected true or false, got " + quotedInput(truth.Scalar()));

  const YAML::Node rig_file = yaml.required(root, "", "rig", "the rig file's name, rig.yaml");
  rig_ = loadRig(folder_ / yaml.string(rig_file, "rig"));

  // Camera order is the CameraFrame::camera index: it must be the rig's, name for name.
  const YAML::Node cameras = yaml.required(root, "", "cameras", "the rig's camera names");
  yaml.requireSequence(cameras, "cameras");
  std::string expected, got;
  bool same = int(cameras.size()) == rig_.cameraCount();
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string name = yaml.string(cameras[i], YamlReader::item("cameras", i));
    got += (got.empty() ? "" : ", ") + name;
    same = same && int(i) < rig_.cameraCount() && rig_.camera(int(i)).name() == name;
  }
  for (const Camera& c : rig_.cameras()) expected += (expected.empty() ? "" : ", ") + c.name();
  if (!same) {
    yaml.fail(cameras, "cameras",
              fmt::format("expected the cameras of {}, in its order: [{}], got [{}]",
                          rig_file.Scalar(), expected, got));
  }
}

void SessionReader::readIndex() {
  const fs::path path = folder_ / "index.csv";
  const std::string file = path.string();
  const std::string text = readFile(path);
  const Lines lines = splitLines(text);
  if (lines.complete.empty()) {
    // The writer's header reaches the disk with the first frame: a crash before it leaves this.
    warnings_.push_back(file + ": no complete line: no frame was recorded");
    return;
  }
  if (lines.complete[0] != "frame,timestamp_ns") {
    throw Error(
        locate(file, 1, "",
               "expected the header 'frame,timestamp_ns', got " + quotedInput(lines.complete[0])));
  }
  int bad_times = 0;
  std::string first_bad_time;
  for (size_t l = 1; l < lines.complete.size(); ++l) {
    const std::string_view line = lines.complete[l];
    const int line_number = int(l) + 1;
    const std::vector<std::string_view> fields = splitFields(line);
    FrameEntry entry{};
    if (fields.size() != 2 || !parseNumber(fields[0], entry.id) ||
        !parseNumber(fields[1], entry.timestamp_ns)) {
      throw Error(
          locate(file, line_number, "",
                 "expected frame,timestamp_ns as two whole numbers, got " + quotedInput(line)));
    }
    if (entry.id < 0) {
      throw Error(locate(file, line_number, "",
                         fmt::format("expected a frame number >= 0, got {}", entry.id)));
    }
    if (!frames_.empty() && entry.id <= frames_.back().id) {
      throw Error(locate(file, line_number, "",
                         fmt::format("frame {} after frame {}: frame numbers must increase",
                                     entry.id, frames_.back().id)));
    }
    // Times from the recording's start: a replay at the recorded rate waits for them. One going
    // back (a camera rebooted mid-take restarts its clock), below 0 or beyond 10 days is taken as
    // the frame before's (it replayed the rest at once, or waited for ever, or overflowed the
    // clock), and said once; the frames are kept.
    constexpr int64_t kTenDaysNs = int64_t(10) * 24 * 3600 * 1'000'000'000;
    const int64_t before = frames_.empty() ? 0 : frames_.back().timestamp_ns;
    if (entry.timestamp_ns < before || entry.timestamp_ns > kTenDaysNs) {
      if (bad_times == 0) {
        first_bad_time = locate(
            file, line_number, "",
            fmt::format("frame {} at {} ns, after {} ns", entry.id, entry.timestamp_ns, before));
      }
      ++bad_times;
      entry.timestamp_ns = before;
    }
    frames_.push_back(entry);
  }
  if (bad_times > 0) {
    warnings_.push_back(fmt::format(
        "{}: {} time{} going back, below 0 or beyond 10 days, each taken as the frame before's "
        "(a camera whose clock restarted?)",
        first_bad_time, bad_times, bad_times == 1 ? "" : "s"));
  }
  if (!lines.torn.empty()) {
    warnings_.push_back(locate(
        file, int(lines.complete.size()) + 1, "",
        fmt::format("torn last line {} (no newline: the recording stopped while writing it); "
                    "ignored, the session ends {}",
                    quotedInput(lines.torn),
                    frames_.empty() ? "before its first frame"
                                    : fmt::format("at frame {}", frames_.back().id))));
  }
}

void SessionReader::checkImages() {
  const int channels = bytesPerPixel(format_);
  // Each frame's first bad image, if any: a run of them at the end is where the recording stopped
  // (a crash, a full disk) and ends the session; one before a whole frame (a damaged file) leaves
  // that frame out, not every frame after it.
  std::vector<std::string> problems(frames_.size());
  size_t whole_end = 0;  // one past the last whole frame
  for (size_t i = 0; i < frames_.size(); ++i) {
    for (int c = 0; c < rig_.cameraCount() && problems[i].empty(); ++c) {
      const Camera& camera = rig_.camera(c);
      const fs::path path = imagePath(c, int(i));
      const Status whole = files_ == ImageFiles::kPnm
                               ? checkPnm(path, camera.width(), camera.height(), channels)
                               : checkPng(path, camera.width(), camera.height(), channels);
      if (!whole.ok())
        problems[i] = path.string() + ": frame " + std::to_string(frames_[i].id) +
                      " is listed in index.csv but its image " + whole.error();
    }
    if (problems[i].empty()) whole_end = i + 1;
  }
  if (whole_end < frames_.size()) {
    warnings_.push_back(
        fmt::format("{}; the session ends {}{}", problems[whole_end],
                    whole_end == 0 ? "before its first frame"
                                   : fmt::format("at frame {}", frames_[whole_end - 1].id),
                    whole_end + 1 < frames_.size()
                        ? fmt::format(", {} later frames ignored", frames_.size() - whole_end - 1)
                        : ""));
  }
  std::vector<FrameEntry> kept;
  kept.reserve(whole_end);
  for (size_t i = 0; i < whole_end; ++i) {
    if (problems[i].empty()) {
      kept.push_back(frames_[i]);
    } else {
      warnings_.push_back(problems[i] + "; that frame is left out, the frames after it are whole");
    }
  }
  frames_ = std::move(kept);
  // Left-overs of a write that never completed: harmless, but worth knowing about.
  for (const Camera& camera : rig_.cameras()) {
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(folder_ / camera.name(), ec)) {
      const std::string name = entry.path().filename().string();
      if (isAtomicWriteLeftover(name)) {
        warnings_.push_back(entry.path().string() +
                            ": left over from an interrupted write; ignored");
      }
    }
    if (ec) {
      throw Error((folder_ / camera.name()).string() +
                  ": cannot list the camera's folder: " + ec.message());
    }
  }
}

fs::path SessionReader::imagePath(int camera, int i) const {
  return folder_ / rig_.camera(camera).name() /
         fmt::format("{:06}.{}", frameId(i), imageFileExtension(files_, format_));
}

fs::path SessionReader::truthMaskPath(int camera, int i) const {
  return folder_ / "truth" / "masks" / rig_.camera(camera).name() /
         fmt::format("{:06}.png", frameId(i));
}

namespace {

// A mask file: one byte a pixel of the camera's size. Throws Error naming it and `what` it is.
std::vector<uint8_t> readMaskFile(const fs::path& file, const Camera& c, const char* what) {
  const cv::Mat mask = existsButIsNotARegularFile(file)
                           ? cv::Mat()
                           : cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (mask.empty() || mask.cols != c.width() || mask.rows != c.height() || !mask.isContinuous())
    throw Error(fmt::format("{}: cannot read the {} ({}x{} PNG, camera {})", file.string(), what,
                            c.width(), c.height(), c.name()));
  return {mask.data, mask.data + mask.total()};
}

}  // namespace

std::vector<uint8_t> SessionReader::readTruthMask(int camera, int i) const {
  return readMaskFile(truthMaskPath(camera, i), rig_.camera(camera), "truth mask");
}

bool SessionReader::hasMasks() const {
  std::error_code ec;
  return fs::is_directory(folder_ / "masks", ec);
}

fs::path SessionReader::maskPath(int camera, int i) const {
  return folder_ / "masks" / rig_.camera(camera).name() / fmt::format("{:06}.png", frameId(i));
}

std::vector<uint8_t> SessionReader::readMask(int camera, int i) const {
  return readMaskFile(maskPath(camera, i), rig_.camera(camera), "actor's mask");
}

int SessionReader::plateFrames(int camera) const {
  int count = 0;
  std::error_code ec;
  while (fs::exists(platePath(camera, count), ec)) ++count;
  return count;
}

fs::path SessionReader::platePath(int camera, int i) const {
  return folder_ / "plate" / rig_.camera(camera).name() /
         fmt::format("{:06}.{}", i, imageFileExtension(files_, format_));
}

Image SessionReader::readPlate(int camera, int i) const {
  Image image;
  const Status read =
      readImageFile(platePath(camera, i), i, rig_.camera(camera), format_, files_, image);
  if (!read.ok()) throw Error("the empty stage's " + read.error());
  return image;
}

bool SessionReader::hasRepairedMasks() const {
  std::error_code ec;
  return fs::is_directory(folder_ / "masks-given", ec);
}

fs::path SessionReader::givenMaskPath(int camera, int i) const {
  return folder_ / (hasRepairedMasks() ? "masks-given" : "masks") / rig_.camera(camera).name() /
         fmt::format("{:06}.png", frameId(i));
}

std::vector<uint8_t> SessionReader::readGivenMask(int camera, int i) const {
  return readMaskFile(givenMaskPath(camera, i), rig_.camera(camera), "given mask");
}

void SessionReader::readMasks(int i, std::vector<CameraFrame>& out,
                              std::vector<std::string>& errors,
                              const std::vector<int>& cameras) const {
  out.resize(rig_.cameraCount());
  errors.resize(rig_.cameraCount());
  const int count = cameras.empty() ? rig_.cameraCount() : static_cast<int>(cameras.size());
  cv::parallel_for_(cv::Range(0, count), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const int c = cameras.empty() ? k : cameras[k];
      const Camera& camera = rig_.camera(c);
      const fs::path path = maskPath(c, i);
      errors[c].clear();
      std::vector<uint8_t>& mask = out[c].mask;
      try {
        const cv::Mat decoded = existsButIsNotARegularFile(path)
                                    ? cv::Mat()
                                    : cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
        if (!decoded.empty() && decoded.cols == camera.width() && decoded.rows == camera.height() &&
            decoded.isContinuous()) {
          mask.assign(decoded.data, decoded.data + decoded.total());  // keeps the buffer
          continue;
        }
      } catch (const cv::Exception&) {
      }
      mask.clear();
      errors[c] =
          fmt::format("{}: frame {}: cannot read the actor's mask ({}x{} PNG, camera {})",
                      path.string(), frameId(i), camera.width(), camera.height(), camera.name());
    }
  });
}

void SessionReader::readFrame(int i, std::vector<CameraFrame>& out,
                              const std::vector<int>& cameras) const {
  const int64_t id = frameId(i), timestamp = timestampNs(i);
  out.resize(rig_.cameraCount());
  const int count = cameras.empty() ? rig_.cameraCount() : static_cast<int>(cameras.size());
  std::vector<Status> errors(count);
  // PNG decoding dominates: cameras in parallel, errors carried out.
  cv::parallel_for_(cv::Range(0, count), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const int c = cameras.empty() ? k : cameras[k];
      const Camera& camera = rig_.camera(c);
      const fs::path path = imagePath(c, i);
      CameraFrame& frame = out[c];
      frame.camera = c;
      frame.frame_id = id;
      frame.timestamp_ns = timestamp;
      errors[k] = readImageFile(path, id, camera, format_, files_, frame.image);
    }
  });
  for (const Status& read : errors) {
    if (!read.ok()) throw Error(read.error());
  }
}

std::vector<std::vector<Eigen::Vector3d>> SessionReader::readTruthJoints(
    std::vector<std::string>* joint_names) const {
  const fs::path path = folder_ / "truth" / "joints.csv";
  const std::string file = path.string();
  if (!truth_) throw Error(file + ": the session has no ground truth (session.yaml: truth: false)");
  const std::string text = readFile(path);
  const Lines lines = splitLines(text);
  if (lines.complete.empty()) throw Error(file + ": empty, expected a header line");
  const std::vector<std::string_view> header = splitFields(lines.complete[0]);
  if (header[0] != "frame" || (header.size() - 1) % 3 != 0) {
    throw Error(locate(file, 1, "",
                       "expected the header frame,NAME_x,NAME_y,NAME_z,..., got " +
                           quotedInput(lines.complete[0])));
  }
  const size_t joints = (header.size() - 1) / 3;
  if (joint_names) {
    joint_names->clear();
    for (size_t j = 0; j < joints; ++j) {
      const std::string_view x = header[1 + 3 * j];
      joint_names->emplace_back(x.substr(0, x.size() >= 2 ? x.size() - 2 : 0));
    }
  }
  // Lines are written before the frame's index line: there may be one for a frame the index
  // does not list (and a torn last one), both ignored.
  std::map<int64_t, std::vector<Eigen::Vector3d>> by_frame;
  for (size_t l = 1; l < lines.complete.size(); ++l) {
    const std::vector<std::string_view> fields = splitFields(lines.complete[l]);
    int64_t id = 0;
    std::vector<Eigen::Vector3d> values(joints);
    bool ok = fields.size() == header.size() && parseNumber(fields[0], id);
    for (size_t k = 1; ok && k < fields.size(); ++k)
      ok = parseNumber(fields[k], values[(k - 1) / 3][int((k - 1) % 3)]);
    if (!ok) {
      throw Error(locate(file, int(l) + 1, "",
                         fmt::format("expected a frame number and {} numbers, got {}", 3 * joints,
                                     quotedInput(lines.complete[l]))));
    }
    by_frame[id] = std::move(values);
  }
  std::vector<std::vector<Eigen::Vector3d>> out;
  out.reserve(frames_.size());
  for (const FrameEntry& frame : frames_) {
    auto found = by_frame.find(frame.id);
    if (found == by_frame.end())
      throw Error(fmt::format("{}: no joints for frame {}, which index.csv lists", file, frame.id));
    out.push_back(std::move(found->second));
  }
  return out;
}

}  // namespace lumistage
