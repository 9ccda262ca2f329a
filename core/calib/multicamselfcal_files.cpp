#include "core/calib/multicamselfcal_files.h"

#include <fmt/format.h>

#include "core/base/atomic_file.h"
#include "core/base/error.h"

namespace lumistage {

namespace fs = std::filesystem;

void writeMultiCamSelfCalInput(const WandSession& session, const fs::path& folder) {
  fs::create_directories(folder);
  std::string points, ids, res;
  for (int c = 0; c < session.cameraCount(); ++c) {
    std::string rows[3];
    std::string& id = ids;
    for (int s = 0; s < session.sampleCount(); ++s) {
      const bool seen = session.has(s, c);
      const Eigen::Vector2d p = seen ? session.pixel(s, c) : Eigen::Vector2d::Zero();
      const char* sep = s ? " " : "";
      rows[0] += seen ? fmt::format("{}{:.4f}", sep, p.x()) : fmt::format("{}NaN", sep);
      rows[1] += seen ? fmt::format("{}{:.4f}", sep, p.y()) : fmt::format("{}NaN", sep);
      rows[2] += seen ? fmt::format("{}1", sep) : fmt::format("{}NaN", sep);
      id += fmt::format("{}{}", sep, seen ? 1 : 0);
    }
    id += "\n";
    for (const std::string& r : rows) points += r + "\n";
    res += fmt::format("{} {}\n", session.cameras()[c].width, session.cameras()[c].height);
  }
  writeFileAtomically(folder / "points.dat", points);
  writeFileAtomically(folder / "IdMat.dat", ids);
  writeFileAtomically(folder / "Res.dat", res);
}

void writeMultiCamSelfCalOutput(const Rig& rig, const fs::path& folder) {
  fs::create_directories(folder);
  for (const Camera& c : rig.cameras()) {
    const Eigen::Matrix<double, 3, 4> P = c.projectionMatrix();
    std::string pmat;
    for (int r = 0; r < 3; ++r) {
      pmat += fmt::format("{:.17g} {:.17g} {:.17g} {:.17g}\n", P(r, 0), P(r, 1), P(r, 2), P(r, 3));
    }
    writeFileAtomically(folder / (c.name() + ".Pmat.cal"), pmat);
    const Eigen::Matrix3d K = c.intrinsics().matrix();
    std::string rad;
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col)
        rad += fmt::format("K{}{} = {:.17g}\n", r + 1, col + 1, K(r, col));
    }
    const Distortion& d = c.distortion();
    if (d.k3 != 0)
      throw Error(
          fmt::format("camera {}: MultiCamSelfCal's .rad has no k3 (it is {})", c.name(), d.k3));
    rad += fmt::format("\nkc1 = {:.17g}\nkc2 = {:.17g}\nkc3 = {:.17g}\nkc4 = {:.17g}\n", d.k1, d.k2,
                       d.p1, d.p2);
    writeFileAtomically(folder / (c.name() + ".rad"), rad);
  }
}

}  // namespace lumistage
