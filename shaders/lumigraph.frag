#version 430 core
// The renderer's own cameras blended with the interpolated lumigraph weights: colour = their
// (despilled) colours' weighted mean, alpha = their share of the weight of every camera of the
// rig (1 when the renderer has them all; less where a foreground mask takes weight away). Images
// are RGBA8, or the colours of a Bayer image's 2x2 cells.
// kOwnCameras is defined when compiling; own camera j's image is layer j of `images`.
in float v_weight[kOwnCameras];
in vec2 v_texel[kOwnCameras];
in float v_total;

uniform sampler2DArray images;
uniform vec2 texel_scale;  // image texel to texture coordinate of `images`
// The own cameras' low-resolution foreground masks, when the renderer has them, each in the corner
// of its layer (cameras of different sizes): a camera's weight scales by its mask where it samples.
uniform sampler2DArray masks;
uniform vec2 mask_scales[kOwnCameras];  // own camera j's pixel to its mask's texture coordinate
uniform int use_masks;
// How far each own camera's green is limited to the larger of its red and blue (the screen's
// spill), 0 to 1: not at all where the desired camera looks from that camera (LumigraphParams).
uniform float despill[kOwnCameras];

out vec4 colour;

// Below this much of the actor where every own camera samples its mask (a twentieth of a cell
// among the four blended), a fragment is clearly off the actor.
const float kClearlyOff = 0.05;

// Bilinear in RGBA images, or, for Bayer images (the array holds their 2x2 cells' colours, cell
// centres at texels 2c + 1), between the colours of the four nearest cells.
vec3 sampleImage(vec2 texel, int layer) {
  return texture(images, vec3(texel * texel_scale, float(layer))).rgb;
}

void main() {
  float own = 0.0, unmasked = 0.0, actor = 0.0, rim = 0.0;
  vec3 rgb = vec3(0.0), rgb_rim = vec3(0.0);
  for (int j = 0; j < kOwnCameras; ++j) {
    float w = v_weight[j];
    if (w <= 0.0) continue;
    vec3 c = sampleImage(v_texel[j], j);
    c.g = mix(c.g, min(c.g, max(c.r, c.b)), despill[j]);
    unmasked += w;
    float m = 1.0;
    // The colour is normalised by the weights, so a partly masked camera would still colour a
    // pixel alone: half a cell off the silhouette (mask 0.5) already counts as off.
    if (use_masks != 0) {
      m = texture(masks, vec3(v_texel[j] * mask_scales[j], float(j))).r;
      actor = max(actor, m);
    }
    // The rim's colour: each camera as near as it sees the actor there (one with no picture this
    // frame, its mask all off, gives none).
    rgb_rim += w * m * c;
    rim += w * m;
    w *= use_masks != 0 ? smoothstep(0.5, 0.75, m) : 1.0;
    rgb += w * c;
    own += w;
  }
  if (v_total <= 0.0 || unmasked <= 0.0) {
    colour = vec4(0.0);
  } else if (own > 0.0) {
    colour = vec4(rgb / own, max(own / v_total, 1.0 / 255.0));  // a masked share stays drawn
  } else if (use_masks != 0 && (actor < kClearlyOff || rim <= 0.0)) {
    // A cell or more off the actor in every own camera (the generic mesh's foot beside the shoe, a
    // mis-posed hand): nothing of the actor is there. Discarded, it writes no depth either, so
    // the mesh behind it (the body behind the hand) or the background shows.
    discard;
  } else {
    // Just off the actor in every own camera (the cells' rim): the cameras' colours weighted by
    // their masks there (those nearest to seeing the actor count most), at a sixteenth of the share, so that a node whose cameras see the actor there outweighs it in the studio's
    // blend, and the silhouette's edge is still drawn where no camera does.
    colour = vec4(rgb_rim / rim, max(unmasked / v_total / 16.0, 1.0 / 255.0));
  }
}
