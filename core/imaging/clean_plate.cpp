#include "core/imaging/clean_plate.h"

#include <algorithm>

namespace lumistage {

std::shared_ptr<const BackgroundModel> learnPlate(const std::vector<Image>& empty, int width,
                                                  int height, int* skipped) {
  const auto fits = [&](const Image& image) {
    return image.width == width && image.height == height;
  };
  const int fitting = int(std::count_if(empty.begin(), empty.end(), fits));
  if (skipped) *skipped = int(empty.size()) - fitting;
  if (fitting == 0) return nullptr;
  auto model = std::make_shared<BackgroundModel>(width, height);
  for (const Image& image : empty)
    if (fits(image)) model->add(image.view());
  model->learn();
  return model;
}

std::shared_ptr<const BackgroundModel> sourcePlate(FrameSource& source, int camera, int* skipped) {
  const Camera& c = source.rig().camera(camera);
  return learnPlate(source.plateImages(camera), c.width(), c.height(), skipped);
}

CameraPlates sessionPlates(const SessionReader& session) {
  const Rig& rig = session.rig();
  CameraPlates plates(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const int frames = session.plateFrames(c);
    std::vector<Image> empty;
    for (int i = 0; i < frames; ++i) empty.push_back(session.readPlate(c, i));
    plates[c] = learnPlate(empty, rig.camera(c).width(), rig.camera(c).height());
  }
  return plates;
}

CameraPlates platesOf(const SessionReader& session, const CameraPlates* given) {
  return given ? *given : sessionPlates(session);
}

}  // namespace lumistage
