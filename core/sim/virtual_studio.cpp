#include "core/sim/virtual_studio.h"

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/body/bvh.h"
#include "core/body/motion_library.h"

namespace lumistage {

VirtualStudio::VirtualStudio(StudioConfig config, int frame_count)
    : config_(std::move(config)), actor_(makeHumanModel(config_.actor)) {
  if (!config_.bvh_file.empty()) {
    clip_ = loadBvh(config_.bvh_file, actor_.skeleton);
  } else {
    const double duration_s = std::max(1.0, config_.placement.start_s + frame_count / config_.fps);
    clip_ = makeBuiltinClip(config_.clip, actor_.skeleton, config_.fps, duration_s);
  }
  if (config_.placement != MotionPlacement{})
    placeMotion(clip_, actor_.skeleton, config_.placement, frame_count, config_.fps);
  gl_ = std::make_unique<EglContext>();
  renderer_ = std::make_unique<StudioRenderer>(actor_);
}

VirtualStudio::~VirtualStudio() {
  renderer_.reset();  // its GL objects go while the context still exists
}

void VirtualStudio::renderFrame(int index, StudioFrame& frame) {
  frame.index = index;
  frame.time_s = index / config_.fps;
  frame.pose = clip_.sample(config_.placement.start_s + frame.time_s);
  actor_.skeleton.jointPositions(frame.pose, frame.joints);
  actor_.skeleton.skinningTransforms(frame.pose, transforms_);
  if (frame.surface.triangles.size() != actor_.rest.triangles.size())
    frame.surface.triangles = actor_.rest.triangles;
  skinMesh(actor_, transforms_, frame.surface.positions, frame.surface.normals);
  renderer_->setSurface(frame.surface.positions, frame.surface.normals);

  const int cameras = config_.rig.cameraCount();
  frame.images.resize(cameras);
  frame.masks.resize(cameras);
  for (int c = 0; c < cameras; ++c) {
    const Camera& camera = config_.rig.camera(c);
    const uint32_t seed =
        config_.seed * 1000003u + static_cast<uint32_t>(index) * 131u + static_cast<uint32_t>(c);
    renderer_->render(camera, config_.look, seed, frame.images[c]);
    const size_t pixels = size_t(camera.width()) * camera.height();
    frame.masks[c].resize(pixels);
    const uint8_t* rgba = frame.images[c].data();
    for (size_t p = 0; p < pixels; ++p) frame.masks[c][p] = rgba[4 * p + 3];
  }
}

void VirtualStudio::renderEmptyStage(int camera, int take, std::vector<uint8_t>& rgba) {
  const uint32_t seed =
      config_.seed * 7919u + 0x9e3779b9u + static_cast<uint32_t>(take) * 131u + camera;
  renderer_->render(config_.rig.camera(camera), config_.look, seed, rgba, /*with_actor=*/false);
}

void writeContactSheet(const Rig& rig, const StudioFrame& frame, const std::filesystem::path& png) {
  const int columns = rig.cameraCount() <= 4 ? rig.cameraCount() : 4;
  const int rows = (rig.cameraCount() + columns - 1) / columns;
  const int w = rig.camera(0).width() / 4, h = rig.camera(0).height() / 4;
  cv::Mat sheet(rows * (h + 4) + 4, columns * (w + 4) + 4, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const Camera& camera = rig.camera(c);
    const cv::Mat rgba(camera.height(), camera.width(), CV_8UC4,
                       const_cast<uint8_t*>(frame.images[c].data()));
    cv::Mat rgb, small;
    cv::cvtColor(rgba, rgb, cv::COLOR_RGBA2RGB);
    cv::resize(rgb, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    const cv::Rect cell(4 + (c % columns) * (w + 4), 4 + (c / columns) * (h + 4), w, h);
    small.copyTo(sheet(cell));
    cv::putText(sheet, camera.name() + " (" + camera.node() + ")", cell.tl() + cv::Point(6, 18),
                cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  writePngAtomically(png, {PixelFormat::kRgb8, sheet.cols, sheet.rows, sheet.data});
}

std::unique_ptr<SessionWriter> openStudioSession(const VirtualStudio& studio,
                                                 const std::filesystem::path& folder) {
  std::vector<std::string> joint_names;
  for (const Joint& joint : studio.actor().skeleton.joints()) joint_names.push_back(joint.name);
  return std::make_unique<SessionWriter>(folder, studio.rig(), studio.config().pixel_format,
                                         studio.config().fps, "virtual-studio", joint_names);
}

void writeStudioPlate(VirtualStudio& studio, int frames, SessionWriter& writer) {
  const int n = studio.rig().cameraCount();
  std::vector<Image> images(n);
  std::vector<ImageView> views(n);
  std::vector<uint8_t> rgba;
  for (int f = 0; f < frames; ++f) {
    for (int c = 0; c < n; ++c) {
      const Camera& camera = studio.rig().camera(c);
      studio.renderEmptyStage(c, f, rgba);
      rgbaToImage(rgba.data(), camera.width(), camera.height(), studio.config().pixel_format,
                  images[c]);
      views[c] = images[c].view();
    }
    writer.writePlate(f, views);
  }
}

void writeStudioFrame(const VirtualStudio& studio, const StudioFrame& frame, int64_t frame_id,
                      SessionWriter& writer, std::vector<Image>& images) {
  const int n = studio.rig().cameraCount();
  images.resize(n);
  std::vector<ImageView> views(n);
  for (int c = 0; c < n; ++c) {
    const Camera& camera = studio.rig().camera(c);
    rgbaToImage(frame.images[c].data(), camera.width(), camera.height(),
                studio.config().pixel_format, images[c]);
    views[c] = images[c].view();
  }
  FrameTruth truth{frame.joints, &frame.surface, &frame.masks};
  writer.writeFrame(frame_id, static_cast<int64_t>(frame.time_s * 1e9 + 0.5), views, &truth);
}

FrameLoop renderFrameLoop(VirtualStudio& studio, int frame_count, PixelFormat format,
                          const std::function<void(int, int)>& progress) {
  FrameLoop loop;
  loop.fps = studio.config().fps;
  loop.frames.resize(studio.rig().cameraCount());
  StudioFrame frame;
  for (int f = 0; f < frame_count; ++f) {
    studio.renderFrame(f, frame);
    for (int c = 0; c < studio.rig().cameraCount(); ++c) {
      const Camera& camera = studio.rig().camera(c);
      Image image;
      rgbaToImage(frame.images[c].data(), camera.width(), camera.height(), format, image);
      loop.frames[c].push_back(std::move(image));
    }
    if (progress) progress(f + 1, frame_count);
  }
  return loop;
}

}  // namespace lumistage
