#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/geometry/rig.h"

namespace lumistage {

// What an import produced, with notes for the user (e.g. how well a distortion model converted).
struct RigImport {
  Rig rig;
  std::vector<std::string> notes;
};

struct RigImportOptions {
  // Imported formats do not say which PC owns which camera. Cameras are dealt to nodes named
  // node1, node2, ... in turn (camera i to node i mod N, N = ceil(cameras / cameras_per_node)),
  // so that every node sees the actor from all around: its partial lumigraph image then covers
  // the whole view and the nodes share any view's work evenly.
  int cameras_per_node = 3;
  // Svoboda's output has no image size; it must be given (OpenCV files carry their own).
  int width = 0;
  int height = 0;
};

// An OpenCV FileStorage file (YAML or XML, as cv::FileStorage writes them). Either one camera at
// the top level or a sequence `cameras` of them; each with camera_matrix (3x3),
// distortion_coefficients (4, 5, or more with the rest zero), image_width, image_height, an
// optional name, and extrinsics as R (3x3) or rvec (Rodrigues), with T or tvec (world to camera).
// Throws Error naming the file, the camera and the missing or malformed key.
RigImport importOpenCvRig(const std::filesystem::path& file, const RigImportOptions& options);

// The output folder of Svoboda's MultiCamSelfCal: one `<name>N.Pmat.cal` (a 3x4 projection matrix
// as text) per camera, optionally `<name>N.rad` beside it (K11..K33, kc1..kc4[,kc5], as written by
// the toolbox and BlueCCal). P is split into K, R, t. MultiCamSelfCal's P maps to *undistorted*
// pixels of the .rad's own K; where that K differs from P's, the distortion is refitted to P's K
// by least squares over the image and the residual is reported in the notes.
RigImport importSvobodaRig(const std::filesystem::path& folder, const RigImportOptions& options);

// A Qualisys Track Manager calibration (.qca.txt, XML; Pose2Sim's demos ship one): each video
// camera's <fov_video> (its image: inclusive pixel bounds), <intrinsic> (focal lengths, principal
// point and distortion in units of 1/64 pixel of the sensor, as Pose2Sim reads them) and
// <transform> (the camera's position in millimetres and a rotation r11..r33, QTM's camera looking
// down its -z). Cameras are named by their serial and ordered naturally (cam2 before cam10);
// inactive cameras and cameras without an <intrinsic> (marker cameras) are left out with a note.
// Throws Error naming the file, line, camera and attribute.
RigImport importQualisysRig(const std::filesystem::path& file, const RigImportOptions& options);

// Pose2Sim's or anipose's calibration (Calib*.toml): a table per camera ([cam_1], [cam_2] ...;
// [metadata] is skipped) with name, size [width, height], matrix (K, 3 rows), distortions (k1 k2
// p1 p2 [k3]), rotation (Rodrigues) and translation (metres, world to camera), OpenCV's
// conventions; cameras in their tables' natural order. A fisheye camera is refused. Throws Error
// naming the file and the table (toml11's own file:line:column for malformed TOML).
RigImport importTomlRig(const std::filesystem::path& file, const RigImportOptions& options);

// EasyMocap's calibration: `folder`/intri.yml (names, K_<name>, dist_<name>: k1 k2 p1 p2 [k3])
// and `folder`/extri.yml (Rot_<name> or the Rodrigues R_<name>, T_<name> in metres, world to
// camera), OpenCV FileStorage files, cameras in the order of `names`. EasyMocap writes no image
// size: W_<name> and H_<name> where present, else options.width and height. Throws Error naming
// the file and key.
RigImport importEasyMocapRig(const std::filesystem::path& folder, const RigImportOptions& options);

// Any calibration a user may hand over, its format told by what it is: a Lumistage rig file
// (`format: lumistage-rig`), a Qualisys `.qca.txt`, a Pose2Sim/anipose `.toml`, an OpenCV
// FileStorage file (any other `.yaml`, `.yml`, `.xml`, `.json`), or a folder of EasyMocap's
// intri.yml and extri.yml, or of MultiCamSelfCal's `*.Pmat.cal` (with options.width and height).
// A rig file comes back as it is written (its own nodes; no notes). Throws Error naming the path
// for anything else, listing what is read.
RigImport importCalibration(const std::filesystem::path& path, const RigImportOptions& options);

// Imported cameras dealt to nodes as RigImportOptions says; throws Error naming `source` for an
// empty list or cameras a rig cannot hold (duplicate names).
Rig assembleImportedRig(std::vector<Camera> cameras, const RigImportOptions& options,
                        const std::string& source);

}  // namespace lumistage
