#version 430 core
// What stands around the stage, a floor and a cylindrical wall, seen through the camera with its
// vignetting and sensor noise: a green screen lit unevenly (folds, hot spots, darker corners) as
// real ones are, or a room (room = 1): a wooden floor, painted walls with posters, a door and a
// skirting board, in colours a person's clothes and skin also have. Alpha 0: not the actor.
in vec2 v_ndc;
uniform mat3 rotation;       // world to camera
uniform vec3 camera_centre;
uniform vec4 focal_centre;   // fx, fy, cx, cy (distortion neglected: the screen is smooth)
uniform vec2 image_size;
uniform uint noise_seed;
uniform float noise_sigma;
uniform vec3 screen_green;
uniform float unevenness;    // 0: flat; 0.15: a typical studio
uniform int room;            // 1: a room instead of the green screen
out vec4 colour;

uint hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
  return x;
}
float hash3(vec3 p) {
  uvec3 q = uvec3(ivec3(floor(p)) + 4096);
  return float(hash(q.x ^ hash(q.y ^ hash(q.z)))) / 4294967295.0;
}
float valueNoise(vec3 p) {
  vec3 i = floor(p), f = fract(p);
  f = f * f * (3.0 - 2.0 * f);
  float a = mix(mix(hash3(i), hash3(i + vec3(1, 0, 0)), f.x), mix(hash3(i + vec3(0, 1, 0)), hash3(i + vec3(1, 1, 0)), f.x), f.y);
  float b = mix(mix(hash3(i + vec3(0, 0, 1)), hash3(i + vec3(1, 0, 1)), f.x), mix(hash3(i + vec3(0, 1, 1)), hash3(i + vec3(1, 1, 1)), f.x), f.y);
  return mix(a, b, f.z);
}
vec3 sensorNoise() {
  uvec2 p = uvec2(gl_FragCoord.xy);
  uint s = hash(p.x * 1973u + p.y * 9277u + noise_seed * 26699u);
  vec3 n;
  for (int c = 0; c < 3; ++c) {
    float u1 = max(float(hash(s + uint(2 * c))) / 4294967295.0, 1e-7);
    float u2 = float(hash(s + uint(2 * c + 1))) / 4294967295.0;
    n[c] = sqrt(-2.0 * log(u1)) * cos(6.2831853 * u2);
    s = hash(s);
  }
  return n * noise_sigma;
}

// The room's colour at `hit` on the floor (ground) or the wall.
vec3 roomColour(vec3 hit, bool ground) {
  if (ground) {
    // Planks 0.18 m wide along x, each its own shade of oak, grain along them, dark joints.
    float plank = floor(hit.y / 0.18);
    float shade = 0.75 + 0.5 * hash3(vec3(plank, 7.0, 3.0));
    float grain = valueNoise(vec3(hit.x * 3.0, hit.y * 60.0, plank)) * 0.25;
    float joint = smoothstep(0.0, 0.006, abs(fract(hit.y / 0.18 + 0.5) - 0.5) * 0.18);
    float end = smoothstep(0.0, 0.004, abs(fract(hit.x / 1.2 + hash3(vec3(plank, 1.0, 1.0))) - 0.5) * 1.2);
    return vec3(0.52, 0.36, 0.22) * shade * (0.85 + grain) * mix(0.35, 1.0, joint * end);
  }
  float angle = atan(hit.y, hit.x);  // around the wall
  float along = angle * 5.0;         // metres along the wall
  vec3 paint = vec3(0.78, 0.74, 0.66) * (0.92 + 0.16 * valueNoise(hit * 2.0));
  if (hit.z < 0.12) return vec3(0.25, 0.22, 0.2);  // skirting board
  // A poster every 2.2 m, 0.9 m wide, from 1.0 to 2.1 m high, a colour of its own, a picture.
  float slot = floor(along / 2.2);
  float u = along - slot * 2.2;
  if (u > 0.4 && u < 1.3 && hit.z > 1.0 && hit.z < 2.1) {
    vec3 hue = vec3(hash3(vec3(slot, 1.0, 0.0)), hash3(vec3(slot, 2.0, 0.0)),
                    hash3(vec3(slot, 3.0, 0.0)));
    float picture = valueNoise(vec3(u * 6.0, hit.z * 6.0, slot));
    return mix(hue, vec3(0.9, 0.88, 0.8), 0.3) * (0.55 + 0.5 * picture);
  }
  // A door every 7 m: 0.9 m wide, 2.05 m high, dark blue with a frame.
  float door = along - floor(along / 7.0) * 7.0;
  if (door > 3.0 && door < 3.9 && hit.z < 2.05) {
    bool frame = door < 3.06 || door > 3.84 || hit.z > 1.99;
    return frame ? vec3(0.9, 0.9, 0.88) : vec3(0.16, 0.22, 0.38);
  }
  return paint;
}

void main() {
  vec2 pixel = (v_ndc + 1.0) * 0.5 * image_size - 0.5;
  vec3 ray_camera = vec3((pixel.x - focal_centre.z) / focal_centre.x, (pixel.y - focal_centre.w) / focal_centre.y, 1.0);
  vec3 ray = normalize(transpose(rotation) * ray_camera);
  // Floor (z = 0) or cyclorama wall (radius 5 m): whichever the ray meets first.
  float t_floor = ray.z < -1e-4 ? -camera_centre.z / ray.z : 1e9;
  float a = dot(ray.xy, ray.xy), b = dot(camera_centre.xy, ray.xy), c = dot(camera_centre.xy, camera_centre.xy) - 25.0;
  float t_wall = a > 1e-8 ? (-b + sqrt(max(b * b - a * c, 0.0))) / a : 1e9;
  vec3 hit = camera_centre + min(t_floor, t_wall) * ray;
  bool on_floor = t_floor < t_wall;
  float shade = on_floor ? 0.88 : 1.0;  // the floor gets less light
  float folds = valueNoise(hit * 1.3) * 0.6 + valueNoise(hit * 4.0) * 0.4;
  float hot = exp(-dot(hit.xy, hit.xy) / 30.0) * 0.08;
  float brightness = shade * (1.0 - unevenness + 2.0 * unevenness * folds) + hot;
  vec2 centred = (pixel - focal_centre.zw) / image_size;
  float vignette = 1.0 - 0.35 * dot(centred, centred);
  vec3 surface = room == 1 ? roomColour(hit, on_floor) : screen_green;
  colour = vec4(clamp(surface * brightness * vignette + sensorNoise(), 0.0, 1.0), 0.0);
}
