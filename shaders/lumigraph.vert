#version 430 core
// Unstructured lumigraph rendering (Buehler et al. 2001, as De Decker & Bekaert 2006 use it), per
// vertex: for every input camera of the rig the texture coordinate (projection with OpenCV lens
// distortion) and the blending weight (docs/lumigraph.md):
//   angle_i  = angle between the rays p->desired and p->c_i, facing_i = cos(n, p->c_i)
//   candidates: cameras that are active, see p (in front, on their image, not occluded: the
//               vertex's visibility mask, VertexVisibility) and face it (facing_i > min_facing)
//   t        = (k+1)-th smallest candidate angle, or max_angle with at most k candidates
//   w_i      = max(0, 1 - angle_i / t) / max(angle_i, epsilon) * smoothstep(min_facing, 1, facing_i)
//              for the k candidates of smallest angle, 0 for every other camera.
// And for the own cameras the shift of the texture coordinate were p misregistration_m further
// along the desired ray, by which the fragment shader divides each camera's weight.
// The desired view rasterises p + dilation * n (texture coordinates and weights stay p's): the flat
// triangles between vertices cut inside a curved surface's silhouette (LumigraphParams).
// The weights are computed in the captured actor's frame: a clone's desired camera is brought
// into it (desired_centre), and only the clone's placement moves the vertex on screen.
// Defined when compiling: kCameras (the rig's), kOwnCameras (the renderer's own cameras, whose
// images it has) and kOwnCameraList (their rig indices).
const int kMaxCameras = 32;
const int kOwn[kOwnCameras] = int[kOwnCameras](kOwnCameraList);
const int kMaxK = 4;

layout(location = 0) in vec3 position;  // captured actor frame (= capture world), metres
layout(location = 1) in vec3 normal;
layout(location = 2) in float dilation;  // metres out along the normal, for the desired view only
layout(location = 3) in uint visible;    // bit i: rig camera i sees the vertex

uniform mat3 rotations[kMaxCameras];
uniform vec3 translations[kMaxCameras];
uniform vec4 focal_centres[kMaxCameras];
uniform float skews[kMaxCameras];
uniform vec3 radials[kMaxCameras];
uniform vec2 tangentials[kMaxCameras];
uniform vec2 image_sizes[kMaxCameras];
uniform vec3 centres[kMaxCameras];
uniform int camera_active[kMaxCameras];  // 0: left out of the blend (leave-one-out)

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
uniform float misregistration_m;  // LumigraphParams; 0: off

out float v_weight[kOwnCameras];  // of the own cameras
out vec2 v_texel[kOwnCameras];    // pixel coordinates + 0.5 (texel space of the camera's image)
out float v_total;                // the weight of every camera of the rig
out vec2 v_shift[kOwnCameras];   // the texel moved by misregistration_m along the desired ray

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
  // Pass 1: every camera's angle (a large value when it cannot contribute) and the k+1 smallest
  // through a branch-free insertion network (no dynamic indexing: llvmpipe runs this 8 vertices
  // at a time).
  const float kNone = 1e9;
  float angle[kCameras], facing[kCameras], weight[kCameras];
  vec4 smallest = vec4(kNone);  // sorted: the 4 smallest angles
  float fifth = kNone;
  for (int i = 0; i < kCameras; ++i) {
    angle[i] = kNone;
    facing[i] = 0.0;
    if (camera_active[i] == 0 || (visible & (1u << i)) == 0u) continue;
    vec3 to_camera = centres[i] - p;
    float f = dot(n, normalize(to_camera));
    if (f <= min_facing) continue;
    float a = angleBetween(to_desired, to_camera);
    angle[i] = a;
    facing[i] = f;
    float x = a, t;
    t = min(smallest.x, x); x = max(smallest.x, x); smallest.x = t;
    t = min(smallest.y, x); x = max(smallest.y, x); smallest.y = t;
    t = min(smallest.z, x); x = max(smallest.z, x); smallest.z = t;
    t = min(smallest.w, x); x = max(smallest.w, x); smallest.w = t;
    fifth = min(fifth, x);
  }
  // Pass 2: the k nearest get the ramp weight, the others 0.
  int k = clamp(k_nearest, 1, kMaxK);
  float kth = k == 1 ? smallest.x : k == 2 ? smallest.y : k == 3 ? smallest.z : smallest.w;
  float next = k == 1 ? smallest.y : k == 2 ? smallest.z : k == 3 ? smallest.w : fifth;
  float threshold = next < kNone ? next : max_angle;
  float sum = 0.0;
  for (int i = 0; i < kCameras; ++i) {
    float a = angle[i];
    float w = 0.0;
    if (a <= kth && a < kNone) {
      float ramp = max(0.0, 1.0 - a / max(threshold, epsilon));
      w = ramp / max(a, epsilon) * smoothstep(min_facing, 1.0, facing[i]);
    }
    weight[i] = w;
    sum += w;
  }
  // The k-th and (k+1)-th tie: every kept weight is 0; the nearest camera alone.
  if (sum <= 0.0 && smallest.x < kNone) {
    for (int i = 0; i < kCameras; ++i) weight[i] = angle[i] == smallest.x ? 1.0 : 0.0;
    sum = 1.0;
  }
  v_total = sum;
  // Where the surface would be were it misregistration_m further along the desired ray.
  vec3 further = p - misregistration_m * normalize(to_desired);
  // Texture coordinates of the own cameras, where the vertex is on their image (occluded or not:
  // across a triangle whose other corners they see, the coordinates stay those of the surface).
  for (int j = 0; j < kOwnCameras; ++j) {
    int i = kOwn[j];
    v_weight[j] = weight[i];
    v_texel[j] = vec2(-1.0);
    v_shift[j] = vec2(0.0);
    vec3 c = rotations[i] * p + translations[i];
    if (c.z <= 0.05) continue;
    vec2 pixel = projectPixel(c, focal_centres[i], skews[i], radials[i], tangentials[i]);
    // Where the camera would read there (the fragment shader weighs the camera by how its image
    // changes over that shift).
    vec3 c_further = rotations[i] * further + translations[i];
    if (misregistration_m > 0.0 && c_further.z > 0.05)
      v_shift[j] =
          projectPixel(c_further, focal_centres[i], skews[i], radials[i], tangentials[i]) - pixel;
    if (all(greaterThanEqual(pixel, vec2(-0.5))) && all(lessThanEqual(pixel, image_sizes[i] - 0.5)))
      v_texel[j] = pixel + 0.5;
  }
  vec3 world = (clone * vec4(p + dilation * n, 1.0)).xyz;
  vec3 c = view_rotation * world + view_translation;
  vec2 pixel = projectPixel(c, view_focal_centre, view_skew, view_radial, view_tangential);
  vec2 ndc = (pixel + 0.5) / view_size * 2.0 - 1.0;
  const float near = 0.05, far = 50.0;
  float z_ndc = (far + near) / (far - near) - 2.0 * far * near / ((far - near) * c.z);
  gl_Position = vec4(ndc * c.z, z_ndc * c.z, c.z);  // w = depth: perspective-correct varyings
}
