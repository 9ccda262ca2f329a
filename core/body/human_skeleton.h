#pragma once

#include <string_view>

#include "core/body/skeleton.h"

namespace lumistage {

// Proportions of a human body. The defaults are the generic human: 1.75 m tall.
struct BodyShape {
  double height_m = 1.75;         // scales everything
  double arm_length_scale = 1.0;  // upper arm, forearm and hand
  double leg_length_scale = 1.0;  // thigh and shin (moves the pelvis up or down)
  double shoulder_width_scale = 1.0;
  double hip_width_scale = 1.0;
  double girth_scale = 1.0;  // every radius of the body's surface
  double belly_scale = 1.0;  // the torso's depth and width at the waist
};

// The 24 joints of the human skeleton, in order (parents first).
enum HumanJoint : int {
  kPelvis,
  kSpine1,
  kSpine2,
  kSpine3,
  kNeck,
  kHead,
  kRightClavicle,
  kRightShoulder,
  kRightElbow,
  kRightWrist,
  kRightHand,
  kLeftClavicle,
  kLeftShoulder,
  kLeftElbow,
  kLeftWrist,
  kLeftHand,
  kRightHip,
  kRightKnee,
  kRightAnkle,
  kRightFoot,
  kLeftHip,
  kLeftKnee,
  kLeftAnkle,
  kLeftFoot,
  kHumanJointCount
};

// The human skeleton in a T-pose (arms level, to the sides), with physiological joint limits;
// hands and feet are end joints (no freedom). Joint names: pelvis, spine1..3, neck, head,
// {right,left}_{clavicle,shoulder,elbow,wrist,hand,hip,knee,ankle,foot}.
Skeleton makeHumanSkeleton(const BodyShape& shape = {});

// How tall a body of this shape stands: the crown of its head above the floor in the rest pose
// (the head joint and the head above it), whatever the legs' share. BodyShape::height_m is this
// only for the generic legs (leg_length_scale 1).
double statureOf(const BodyShape& shape);

// Throws std::invalid_argument, naming `source` and the first joint out of place, unless `skeleton`
// has the human skeleton's joints in its order (HumanJoint): the tracker and the nodes' posed body
// index joints by that order, and a file that lists them otherwise (another exporter's order of a
// node's children) would pose a contorted body without a word.
void checkHumanJointOrder(const Skeleton& skeleton, std::string_view source);

}  // namespace lumistage
