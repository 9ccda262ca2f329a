#include "core/imaging/clean_plate.h"

namespace lumistage {

std::shared_ptr<const BackgroundModel> learnPlate(const std::vector<Image>& empty, int width,
                                                  int height, int* skipped) {
  auto model = std::make_shared<BackgroundModel>(width, height);
  int left_out = 0;
  for (const Image& image : empty) {
    if (image.width != width || image.height != height) {
      ++left_out;
      continue;
    }
    model->add(image.view());
  }
  if (skipped) *skipped = left_out;
  if (model->frames() == 0) return nullptr;
  model->learn();
  return model;
}

CameraPlates sessionPlates(const SessionReader& session) {
  const Rig& rig = session.rig();
  CameraPlates plates(rig.cameraCount());
  for (int c = 0; c < rig.cameraCount(); ++c) {
    const int frames = session.plateFrames(c);
    if (frames == 0) continue;
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
