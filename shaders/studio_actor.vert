#version 430 core
// The virtual studio's actor seen by one calibrated camera. Lens distortion is applied per
// vertex (OpenCV's model, as in core/geometry/camera.h); the actor's triangles are a few pixels
// across, so straight edges between distorted vertices are exact to a small fraction of a pixel.
layout(location = 0) in vec3 position;       // posed, world, metres
layout(location = 1) in vec3 normal;         // posed, world
layout(location = 2) in vec3 rest_position;  // rest pose: where the surface pattern is anchored
layout(location = 3) in float material;

uniform mat3 rotation;      // world to camera
uniform vec3 translation;
uniform vec4 focal_centre;  // fx, fy, cx, cy
uniform float skew;
uniform float radial[3];    // k1, k2, k3
uniform vec2 tangential;    // p1, p2
uniform vec2 image_size;
uniform vec2 depth_range;   // near, far in metres

out vec3 v_world;
out vec3 v_normal;
out vec3 v_rest;
flat out int v_material;

void main() {
  vec3 c = rotation * position + translation;
  vec2 x = c.xy / c.z;
  float r2 = dot(x, x);
  float k = 1.0 + r2 * (radial[0] + r2 * (radial[1] + r2 * radial[2]));
  vec2 xd = x * k + vec2(2.0 * tangential.x * x.x * x.y + tangential.y * (r2 + 2.0 * x.x * x.x),
                         tangential.x * (r2 + 2.0 * x.y * x.y) + 2.0 * tangential.y * x.x * x.y);
  vec2 pixel = vec2(focal_centre.x * xd.x + skew * xd.y + focal_centre.z, focal_centre.y * xd.y + focal_centre.w);
  // Pixel centres at +0.5; image row 0 at the bottom of the framebuffer, so that glReadPixels
  // returns rows top first, as images are stored.
  vec2 ndc = (pixel + 0.5) / image_size * 2.0 - 1.0;
  float n = depth_range.x, f = depth_range.y;
  float z_ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * c.z);
  gl_Position = vec4(ndc * c.z, z_ndc * c.z, c.z);  // w = depth: perspective-correct varyings
  v_world = position;
  v_normal = normal;
  v_rest = rest_position;
  v_material = int(material + 0.5);
}
