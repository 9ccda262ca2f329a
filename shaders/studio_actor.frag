#version 430 core
// The actor's surface: a procedural texture per material anchored on the rest pose (so it moves
// with the body and gives photo-consistency something to see), lit by the studio's lights, with
// green spill at grazing angles and sensor noise. Alpha 1 marks the actor (the truth mask).
in vec3 v_world;
in vec3 v_normal;
in vec3 v_rest;
flat in int v_material;

uniform vec3 camera_centre;
uniform uint noise_seed;
uniform float noise_sigma;  // in 0..1 units
uniform float spill;        // green spill strength

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
// Gaussian sensor noise from the pixel, the frame and the camera (Box-Muller).
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

// A camera's pixel integrates the light over its area (and its lens blurs): the pattern's sharp
// edges are box-filtered over the pixel's footprint (fwidth), as a sensor would record them, not
// point-sampled into stair-steps that no other view could reproduce.
// The mean of step(edge, fract(x)) over [x - w/2, x + w/2]: the integral of the square wave is
// floor(x) * (1 - edge) + max(fract(x) - edge, 0).
float filteredSquare(float x, float edge) {
  float w = max(fwidth(x), 1e-6);
  float a = x - 0.5 * w, b = x + 0.5 * w;
  float ia = floor(a) * (1.0 - edge) + max(fract(a) - edge, 0.0);
  float ib = floor(b) * (1.0 - edge) + max(fract(b) - edge, 0.0);
  return (ib - ia) / w;
}
// The share of the pixel's footprint where lo <= x <= hi.
float filteredInterval(float x, float lo, float hi) {
  float w = max(fwidth(x), 1e-6);
  return clamp((min(x + 0.5 * w, hi) - max(x - 0.5 * w, lo)) / w, 0.0, 1.0);
}
// The mean of sin over the footprint of phase x: sin(x) * sinc(w / 2).
float filteredSin(float x) {
  float h = 0.5 * max(fwidth(x), 1e-6);
  return sin(x) * sin(h) / h;
}

vec3 albedo() {
  vec3 p = v_rest;
  float fine = valueNoise(p * 180.0);   // ~5 mm grain
  float mid = valueNoise(p * 40.0);
  if (v_material == 1) {  // shirt: red and cream horizontal stripes, a printed band on the chest
    float stripe = filteredSquare(p.z * 14.0, 0.5);
    vec3 c = mix(vec3(0.70, 0.12, 0.10), vec3(0.88, 0.82, 0.68), stripe);
    float band = filteredInterval(p.z, 1.26, 1.34) * filteredInterval(p.y, 0.0, 1e3);
    c = mix(c, vec3(0.10, 0.25, 0.75), band * filteredSquare(p.x * 20.0, 0.5));
    return c * (0.85 + 0.25 * fine);
  }
  if (v_material == 2) {  // trousers: denim with a diagonal twill
    float twill = 0.5 + 0.5 * filteredSin((p.x + p.z) * 900.0);
    return vec3(0.12, 0.20, 0.42) * (0.75 + 0.2 * twill + 0.3 * fine);
  }
  if (v_material == 3) return vec3(0.18, 0.11, 0.06) * (0.7 + 0.6 * fine);  // hair
  if (v_material == 4) {  // shoes, with a few light specks
    float w = max(fwidth(fine), 1e-4);
    float speck = clamp((fine - 0.985) / w + 0.5, 0.0, 1.0);
    return vec3(0.10, 0.10, 0.11) * (0.8 + 0.4 * mid) + 0.25 * speck;
  }
  return vec3(0.86, 0.64, 0.52) * (0.9 + 0.1 * mid + 0.08 * fine);  // skin
}

void main() {
  vec3 n = normalize(v_normal);
  vec3 to_camera = normalize(camera_centre - v_world);
  // Key light high in front-right, fill from the left, soft ambient from the studio.
  vec3 key = normalize(vec3(0.4, 0.6, 0.7)), fill = normalize(vec3(-0.6, 0.3, 0.4));
  float light = 0.42 + 0.5 * max(dot(n, key), 0.0) + 0.22 * max(dot(n, fill), 0.0);
  vec3 rgb = albedo() * light;
  // Green spill: light bounced off the green screen reaches the actor's silhouette edges.
  float grazing = pow(1.0 - abs(dot(n, to_camera)), 3.0);
  rgb += spill * grazing * vec3(-0.05, 0.22, -0.04);
  colour = vec4(clamp(rgb + sensorNoise(), 0.0, 1.0), 1.0);
}
