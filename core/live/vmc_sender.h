#pragma once

#include <Eigen/Geometry>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/body/skeleton.h"
#include "core/net/message_types.h"

namespace lumistage {

// Where a live feed goes: a host (name, IPv4, or IPv6 in brackets) and a UDP port.
struct OscTarget {
  std::string host;
  int port = 0;
  std::string text() const;  // "host:port", IPv6 in brackets
};

// "HOST:PORT" ("127.0.0.1:39539", "studio-pc:39539", "[::1]:39539"). Throws Error saying what is
// wrong (no port, a port that is not 1..65535, no host) and what is expected.
OscTarget parseOscTarget(std::string_view text);

// Unity's axes from ours. Ours: right-handed, metres, z up, the actor facing +y, +x the actor's
// right. Unity's: left-handed, metres, Y up, a humanoid facing +Z, +X its right. So X = x, Y = z,
// Z = y: a swap of two axes, S = S^-1, a reflection (det -1) that is the change of handedness.
// A position maps as S p; a rotation R as S R S, a proper rotation again, whose quaternion is
// (x, y, z, w) -> (-x, -z, -y, w) of ours: the axis mapped by S, the angle's sign turned (a turn
// counter-clockwise about ours is clockwise about Unity's, seen from the same side).
Eigen::Vector3d toUnityPosition(const Eigen::Vector3d& ours);
Eigen::Quaterniond toUnityRotation(const Eigen::Matrix3d& ours);  // w >= 0

// A Unity humanoid bone (HumanBodyBones' name) as VMC's /VMC/Ext/Bone/Pos gives it: its local
// position and rotation relative to its parent bone, Unity's axes (toUnityPosition).
struct VmcBone {
  const char* name = "";
  int joint = -1;   // ours
  int parent = -1;  // in the bones sent; -1 for Hips (whose parent is the root)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

// The tracked skeleton streamed live in the VMC protocol (protocol.vmc.info: OSC over UDP, what
// VSeeFace, EVMC4U for Unity, VMC4UE for Unreal and the Blender add-ons receive, commonly on port
// 39539), one OSC bundle a frame:
//   /VMC/Ext/Root/Pos "root" 0 0 0  0 0 0 1   (the stage's origin, the floor's centre)
//   /VMC/Ext/Bone/Pos NAME px py pz qx qy qz qw   for each humanoid bone we have, parents first
//   /VMC/Ext/OK 1 STATE 0      (loaded; 3 calibrated: the actor tracked, else 0; normal mode)
//   /VMC/Ext/T SECONDS         (since the sender was made)
// Our joints map onto Unity's humanoid bones by name (pelvis Hips, spine1..3 Spine, Chest,
// UpperChest, neck Neck, head Head, clavicle Shoulder, shoulder UpperArm, elbow LowerArm, wrist
// Hand, hip UpperLeg, knee LowerLeg, ankle Foot, foot Toes; left and right); the hands' end joints
// have none. Our rest pose has every joint's frame aligned with the world, as a VRM model's
// normalised T-pose has every bone's: identity rotations are a T-pose on both sides.
//
// The OSC is liblo's; the bundle and its messages are made once and their numbers written in
// place each frame, and each bundle goes out with one sendto() that never waits (MSG_DONTWAIT on a
// UDP socket): a receiver that is not there, or a full socket buffer, loses that frame's bundle and
// nothing else, said in the log at most once every 10 seconds.
class VmcSender {
 public:
  static constexpr int kDefaultPort = 39539;  // VMC's marionette port
  // Throws Error: a host that does not resolve, no socket, or a skeleton without a pelvis.
  VmcSender(const OscTarget& target, const Skeleton& skeleton);
  ~VmcSender();
  VmcSender(const VmcSender&) = delete;
  VmcSender& operator=(const VmcSender&) = delete;

  // The frame's bundle for `pose` (as the studio sends it to the nodes: the skeleton's angles, its
  // root, the scale about the stage's origin, posed_body.h); `tracked`: the tracker found the
  // actor. Never blocks nor throws; false when the bundle was not sent.
  bool send(const PoseData& pose, bool tracked);
  // The bones as the last send() wrote them (Unity's axes), parents first.
  const std::vector<VmcBone>& bones() const { return bones_; }
  const OscTarget& target() const { return target_; }
  int64_t bundlesSent() const { return sent_; }
  int64_t bundlesLost() const { return lost_; }
  size_t bundleBytes() const { return packet_.size(); }  // each frame's datagram

 private:
  struct Osc;  // liblo's bundle and messages
  void writeBones(const PoseData& pose);
  OscTarget target_;
  Skeleton skeleton_;
  std::vector<VmcBone> bones_;
  std::unique_ptr<Osc> osc_;
  int socket_ = -1;
  std::vector<uint8_t> address_;  // sockaddr of the target
  std::vector<uint8_t> packet_;   // the serialised bundle, reused
  Pose pose_;
  std::vector<Eigen::Isometry3d> global_;
  std::chrono::steady_clock::time_point start_, told_{};
  int64_t sent_ = 0, lost_ = 0, lost_untold_ = 0;
};

}  // namespace lumistage
