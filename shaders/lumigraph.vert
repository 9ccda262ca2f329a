#version 430 core
// Unstructured lumigraph rendering (Buehler et al. 2001, as De Decker & Bekaert 2006 use it), per
// vertex: for every input camera of the rig the texture coordinate (projection with OpenCV lens
// distortion) and the blending weight (docs/lumigraph.md):
//   angle_i  = angle between the rays p->desired and p->c_i, facing_i = cos(n, p->c_i)
//   candidates: cameras that are active, see p on their image, face it (facing_i > min_facing)
//               and are not occluded (camera depth <= depth map + tolerance)
//   t        = (k+1)-th smallest candidate angle, or max_angle with at most k candidates
//   w_i      = max(0, 1 - angle_i / t) / max(angle_i, epsilon) * smoothstep(min_facing, 1, facing_i)
//              for the k candidates of smallest angle, 0 for every other camera.
// The weights are computed in the captured actor's frame: a clone's desired camera is brought
// into it (desired_centre), and only the clone's placement moves the vertex on screen.
const int kMaxCameras = 16;
const int kMaxK = 4;

layout(location = 0) in vec3 position;  // captured actor frame (= capture world), metres
layout(location = 1) in vec3 normal;

uniform int camera_count;
uniform mat3 rotations[kMaxCameras];
uniform vec3 translations[kMaxCameras];
uniform vec4 focal_centres[kMaxCameras];
uniform float skews[kMaxCameras];
uniform vec3 radials[kMaxCameras];
uniform vec2 tangentials[kMaxCameras];
uniform vec2 image_sizes[kMaxCameras];
uniform vec3 centres[kMaxCameras];
uniform int camera_active[kMaxCameras];  // 0: left out of the blend (leave-one-out)

uniform sampler2DArray depth_maps;  // camera-space depth, one layer per rig camera
uniform float depth_scale;          // depth-map texels per camera pixel
uniform vec2 depth_map_size;
uniform float depth_tolerance;

uniform int k_nearest;
uniform float min_facing;
uniform float max_angle;
uniform float epsilon;

uniform mat4 clone;          // stage (world) from the captured actor frame
uniform vec3 desired_centre;  // the desired camera's centre in the captured actor frame
uniform mat3 view_rotation;   // the desired camera: world to camera
uniform vec3 view_translation;
uniform vec4 view_focal_centre;
uniform float view_skew;
uniform vec3 view_radial;
uniform vec2 view_tangential;
uniform vec2 view_size;

out float v_weight[kMaxCameras];
out vec2 v_texel[kMaxCameras];  // pixel coordinates + 0.5 (texel space of the camera's image)

vec2 projectPixel(vec3 c, vec4 fc, float s, vec3 radial, vec2 tangential) {
  vec2 x = c.xy / c.z;
  float r2 = dot(x, x);
  float k = 1.0 + r2 * (radial.x + r2 * (radial.y + r2 * radial.z));
  vec2 xd = x * k + vec2(2.0 * tangential.x * x.x * x.y + tangential.y * (r2 + 2.0 * x.x * x.x),
                         tangential.x * (r2 + 2.0 * x.y * x.y) + 2.0 * tangential.y * x.x * x.y);
  return vec2(fc.x * xd.x + s * xd.y + fc.z, fc.y * xd.y + fc.w);
}

float angleBetween(vec3 a, vec3 b) { return atan(length(cross(a, b)), dot(a, b)); }

void main() {
  vec3 p = position;
  vec3 n = normalize(normal);
  vec3 to_desired = desired_centre - p;
  float best_angle[kMaxK + 1];
  int best_camera[kMaxK + 1];
  float best_facing[kMaxK + 1];
  int count = 0;
  int keep = min(k_nearest, kMaxK) + 1;
  for (int i = 0; i < kMaxCameras; ++i) {
    v_weight[i] = 0.0;
    v_texel[i] = vec2(-1.0);
    if (i >= camera_count || camera_active[i] == 0) continue;
    vec3 c = rotations[i] * p + translations[i];
    if (c.z <= 0.05) continue;
    vec2 pixel = projectPixel(c, focal_centres[i], skews[i], radials[i], tangentials[i]);
    if (any(lessThan(pixel, vec2(-0.5))) || any(greaterThan(pixel, image_sizes[i] - 0.5)))
      continue;
    v_texel[i] = pixel + 0.5;
    vec3 to_camera = centres[i] - p;
    float facing = dot(n, normalize(to_camera));
    if (facing <= min_facing) continue;
    vec4 d = textureGather(depth_maps, vec3(v_texel[i] * depth_scale / depth_map_size, float(i)));
    if (c.z > min(min(d.x, d.y), min(d.z, d.w)) + depth_tolerance) continue;  // occluded
    float a = angleBetween(to_desired, to_camera);
    // Insert into the sorted list of the k+1 smallest angles.
    int j = min(count, keep - 1);
    if (count >= keep && a >= best_angle[keep - 1]) continue;
    while (j > 0 && best_angle[j - 1] > a) {
      best_angle[j] = best_angle[j - 1];
      best_camera[j] = best_camera[j - 1];
      best_facing[j] = best_facing[j - 1];
      --j;
    }
    best_angle[j] = a;
    best_camera[j] = i;
    best_facing[j] = facing;
    count = min(count + 1, keep);
  }
  int k = min(k_nearest, kMaxK);
  float threshold = count > k ? best_angle[k] : max_angle;
  float sum = 0.0;
  for (int j = 0; j < kMaxK; ++j) {
    if (j >= min(k, count)) break;
    float a = best_angle[j];
    float ramp = max(0.0, 1.0 - a / max(threshold, epsilon));
    float w = ramp / max(a, epsilon) * smoothstep(min_facing, 1.0, best_facing[j]);
    v_weight[best_camera[j]] = w;
    sum += w;
  }
  // The k-th and (k+1)-th tie: every kept weight is 0; the nearest camera alone.
  if (count > 0 && sum <= 0.0) v_weight[best_camera[0]] = 1.0;

  vec3 world = (clone * vec4(p, 1.0)).xyz;
  vec3 c = view_rotation * world + view_translation;
  vec2 pixel = projectPixel(c, view_focal_centre, view_skew, view_radial, view_tangential);
  vec2 ndc = (pixel + 0.5) / view_size * 2.0 - 1.0;
  const float near = 0.05, far = 50.0;
  float z_ndc = (far + near) / (far - near) - 2.0 * far * near / ((far - near) * c.z);
  gl_Position = vec4(ndc * c.z, z_ndc * c.z, c.z);  // w = depth: perspective-correct varyings
}
