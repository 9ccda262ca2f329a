#version 430 core
// The renderer's own cameras blended with the interpolated lumigraph weights: colour = their
// weighted mean, alpha = their share of the weight of every camera of the rig (1 when the
// renderer has them all). Images are RGBA8, or Bayer (one byte a pixel) demosaiced here.
const int kMaxCameras = 16;

in float v_weight[kMaxCameras];
in vec2 v_texel[kMaxCameras];

uniform int camera_count;
uniform int own_layer[kMaxCameras];  // layer of each rig camera's image in `images`, -1: not ours
uniform sampler2DArray images;
uniform vec2 images_size;  // texels of the array (the largest camera)
uniform int bayer;         // 0: RGBA; 1: Bayer, R at red_offset in each 2x2 cell
uniform ivec2 red_offset;

out vec4 colour;

vec3 cellColour(ivec2 cell, int layer) {
  ivec2 o = cell * 2;
  ivec2 r = o + red_offset, b = o + (ivec2(1) - red_offset);
  ivec2 g1 = o + ivec2(1 - red_offset.x, red_offset.y), g2 = o + ivec2(red_offset.x, 1 - red_offset.y);
  return vec3(texelFetch(images, ivec3(r, layer), 0).r,
              0.5 * (texelFetch(images, ivec3(g1, layer), 0).r + texelFetch(images, ivec3(g2, layer), 0).r),
              texelFetch(images, ivec3(b, layer), 0).r);
}

vec3 sampleImage(vec2 texel, int layer) {
  if (bayer == 0) return texture(images, vec3(texel / images_size, float(layer))).rgb;
  // Bilinear between the colours of the four nearest 2x2 cells (cell centres at 2c + 1 texels).
  vec2 s = (texel - 1.0) * 0.5;
  ivec2 c0 = ivec2(floor(s));
  vec2 f = s - vec2(c0);
  ivec2 last = ivec2(images_size) / 2 - 1;
  ivec2 a = clamp(c0, ivec2(0), last), b = clamp(c0 + 1, ivec2(0), last);
  return mix(mix(cellColour(a, layer), cellColour(ivec2(b.x, a.y), layer), f.x),
             mix(cellColour(ivec2(a.x, b.y), layer), cellColour(b, layer), f.x), f.y);
}

void main() {
  float total = 0.0, own = 0.0;
  vec3 rgb = vec3(0.0);
  for (int i = 0; i < kMaxCameras; ++i) {
    if (i >= camera_count) break;
    float w = v_weight[i];
    total += w;
    if (w <= 0.0 || own_layer[i] < 0) continue;
    rgb += w * sampleImage(v_texel[i], own_layer[i]);
    own += w;
  }
  colour = own > 0.0 && total > 0.0 ? vec4(rgb / own, own / total) : vec4(0.0);
}
