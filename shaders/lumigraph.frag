#version 430 core
// The renderer's own cameras blended with the interpolated lumigraph weights: colour = their
// weighted mean, alpha = their share of the weight of every camera of the rig (1 when the
// renderer has them all; less where a foreground mask takes weight away). Images are RGBA8, or
// Bayer (one byte a pixel) demosaiced here.
// kOwnCameras is defined when compiling; own camera j's image is layer j of `images`.
in float v_weight[kOwnCameras];
in vec2 v_texel[kOwnCameras];
in float v_total;

uniform sampler2DArray images;
uniform vec2 images_size;  // texels of the array (the largest camera)
uniform int bayer;         // 0: RGBA; 1: Bayer, R at red_index in each 2x2 cell
uniform int red_index;     // 0: top left, 1: top right, 2: bottom left, 3: bottom right
// The own cameras' low-resolution foreground masks (cells covering the image as the image array
// does), when the renderer has them: a camera's weight scales by its mask where it samples.
uniform sampler2DArray masks;
uniform int use_masks;

out vec4 colour;

// A 2x2 Bayer cell's colour (R, mean of the two G, B) from one gather of its four texels.
vec3 cellColour(ivec2 cell, float layer) {
  vec4 g = textureGather(images, vec3((vec2(cell * 2) + 1.0) / images_size, layer));
  vec4 q = vec4(g.w, g.z, g.x, g.y);  // top left, top right, bottom left, bottom right
  float r = q[red_index], b = q[3 - red_index];
  return vec3(r, 0.5 * (q.x + q.y + q.z + q.w - r - b), b);
}

vec3 sampleImage(vec2 texel, int layer) {
  if (bayer == 0) return texture(images, vec3(texel / images_size, float(layer))).rgb;
  // Bilinear between the colours of the four nearest 2x2 cells (cell centres at 2c + 1 texels).
  vec2 s = (texel - 1.0) * 0.5;
  ivec2 c0 = ivec2(floor(s));
  vec2 f = s - vec2(c0);
  ivec2 last = ivec2(images_size) / 2 - 1;
  ivec2 a = clamp(c0, ivec2(0), last), b = clamp(c0 + 1, ivec2(0), last);
  float l = float(layer);
  return mix(mix(cellColour(a, l), cellColour(ivec2(b.x, a.y), l), f.x),
             mix(cellColour(ivec2(a.x, b.y), l), cellColour(b, l), f.x), f.y);
}

void main() {
  float own = 0.0, unmasked = 0.0;
  vec3 rgb = vec3(0.0), rgb_unmasked = vec3(0.0);
  for (int j = 0; j < kOwnCameras; ++j) {
    float w = v_weight[j];
    if (w <= 0.0) continue;
    vec3 c = sampleImage(v_texel[j], j);
    rgb_unmasked += w * c;
    unmasked += w;
    // The colour is normalised by the weights, so a partly masked camera would still colour a
    // pixel alone: half a cell off the silhouette (mask 0.5) already counts as off.
    if (use_masks != 0)
      w *= smoothstep(0.5, 0.75, texture(masks, vec3(v_texel[j] / images_size, float(j))).r);
    rgb += w * c;
    own += w;
  }
  if (v_total <= 0.0 || unmasked <= 0.0) {
    colour = vec4(0.0);
  } else if (own > 0.0) {
    colour = vec4(rgb / own, max(own / v_total, 1.0 / 255.0));  // a masked share stays drawn
  } else {
    // Off the actor in every own camera: the unmasked colour, at a sixteenth of the share, so that
    // a node whose cameras see the actor there outweighs it in the studio's blend, and the pixel is
    // still drawn where no camera does (a hole would show more than the screen's colour).
    colour = vec4(rgb_unmasked / unmasked, max(unmasked / v_total / 16.0, 1.0 / 255.0));
  }
}
