#version 430 core
// The mesh's depth as one input camera sees it, lens distortion included, into a small map that
// the lumigraph's visibility test reads (lumigraph.vert). Positions are in the captured actor's
// frame (the world of the capture).
layout(location = 0) in vec3 position;

uniform mat3 rotation;  // world to camera
uniform vec3 translation;
uniform vec4 focal_centre;  // fx, fy, cx, cy
uniform float skew;
uniform vec3 radial;      // k1, k2, k3
uniform vec2 tangential;  // p1, p2
uniform vec2 image_size;  // the camera's, pixels
uniform float map_scale;  // depth-map texels per camera pixel
uniform vec2 map_size;    // texels

out float v_depth;

vec2 projectPixel(vec3 c) {
  vec2 x = c.xy / c.z;
  float r2 = dot(x, x);
  float k = 1.0 + r2 * (radial.x + r2 * (radial.y + r2 * radial.z));
  vec2 xd = x * k + vec2(2.0 * tangential.x * x.x * x.y + tangential.y * (r2 + 2.0 * x.x * x.x),
                         tangential.x * (r2 + 2.0 * x.y * x.y) + 2.0 * tangential.y * x.x * x.y);
  return vec2(focal_centre.x * xd.x + skew * xd.y + focal_centre.z,
              focal_centre.y * xd.y + focal_centre.w);
}

void main() {
  vec3 c = rotation * position + translation;
  vec2 texel = (projectPixel(c) + 0.5) * map_scale;
  vec2 ndc = texel / map_size * 2.0 - 1.0;
  const float n = 0.05, f = 50.0;
  float z_ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * c.z);
  gl_Position = vec4(ndc * c.z, z_ndc * c.z, c.z);
  v_depth = c.z;
}
