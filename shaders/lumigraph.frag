#version 430 core
// The renderer's own cameras blended with the interpolated lumigraph weights, each divided by its
// expected misregistration here: colour = their (despilled) colours' weighted mean, alpha = their
// share of the undivided weight of every camera of the rig, on a log scale (shareAlpha). Images
// are RGBA8, the colours of a Bayer image's 2x2 cells, or Bayer mosaics demosaiced here.
// kOwnCameras and kAlphaStepsPerOctave are defined when compiling; own camera j's image is layer
// j of `images`.
in float v_weight[kOwnCameras];
in vec2 v_texel[kOwnCameras];
in float v_total;
in vec2 v_shift[kOwnCameras];  // own camera j's texel moved by misregistration_m along the ray

uniform float misregistration_m;
uniform float misregistration_noise;  // colour difference (0 to 1) below which it counts little
const float kMaxShift = 4.0;          // pixels

uniform sampler2DArray images;
uniform vec2 texel_scale;  // image texel to texture coordinate of `images`
#ifdef kMosaic
// `images` holds Bayer mosaics (one byte a pixel; kMosaic defined when compiling, a program of its
// own: a branch on a uniform costs llvmpipe as much as the demosaic): own camera j's of
// mosaic_size[j] pixels, with R at mosaic_red[j] in each 2x2 cell.
uniform ivec2 mosaic_red[kOwnCameras];
uniform ivec2 mosaic_size[kOwnCameras];
#endif
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

#ifdef kMosaic
// Own camera j's Bayer mosaic demosaiced at full resolution, bilinearly (each pixel's missing
// colours the mean of its nearest pixels of that colour: OpenCV's demosaic, as `lumistage eval`
// shows a camera's image), then interpolated bilinearly between the four pixels around the texel
// (as a filtered texture of the demosaiced image). The 4x4 pixels around the texel in four
// gathers; the image's outermost pixels are read as their neighbours further in (the gathers
// stay on the image).
vec3 sampleImage(vec2 texel, int j) {
  ivec2 size = mosaic_size[j];
  vec2 p = clamp(texel - 0.5, vec2(1.0), vec2(size - 2));
  ivec2 base = min(ivec2(p), size - 3);
  vec2 f = p - vec2(base);
  // Each gather: (x0, y1), (x1, y1), (x1, y0), (x0, y0) of the 2x2 pixels around its corner.
  vec2 corner = vec2(base) * texel_scale;
  vec4 g00 = textureGather(images, vec3(corner, float(j)));
  vec4 g10 = textureGather(images, vec3(corner + vec2(2.0, 0.0) * texel_scale, float(j)));
  vec4 g01 = textureGather(images, vec3(corner + vec2(0.0, 2.0) * texel_scale, float(j)));
  vec4 g11 = textureGather(images, vec3(corner + vec2(2.0) * texel_scale, float(j)));
  float v[16] = float[16](g00.w, g00.z, g10.w, g10.z,  // rows base.y - 1 to base.y + 2,
                          g00.x, g00.y, g10.x, g10.y,  // columns base.x - 1 to base.x + 2
                          g01.w, g01.z, g11.w, g11.z,
                          g01.x, g01.y, g11.x, g11.y);
  vec3 c[4];
  for (int k = 0; k < 4; ++k) {
    int x = 1 + (k & 1), y = 1 + (k >> 1), i = 4 * y + x;
    float own = v[i];
    float across = 0.5 * (v[i - 1] + v[i + 1]), along = 0.5 * (v[i - 4] + v[i + 4]);
    float plus = 0.5 * (across + along);
    float diagonal = 0.25 * (v[i - 5] + v[i - 3] + v[i + 3] + v[i + 5]);
    ivec2 site = (base + ivec2(x - 1, y - 1) - mosaic_red[j]) & 1;  // (0, 0): R, (1, 1): B
    c[k] = site.x == site.y ? (site.x == 0 ? vec3(own, plus, diagonal) : vec3(diagonal, plus, own))
                            : (site.x == 1 ? vec3(across, own, along) : vec3(along, own, across));
  }
  return mix(mix(c[0], c[1], f.x), mix(c[2], c[3], f.x), f.y);
}

#else
// Bilinear in RGBA images, or, for Bayer images (the array holds their 2x2 cells' colours, cell
// centres at texels 2c + 1), between the colours of the four nearest cells.
vec3 sampleImage(vec2 texel, int layer) {
  return texture(images, vec3(texel * texel_scale, float(layer))).rgb;
}
#endif

// A share of the weight (0 to 1) as the alpha byte, on a logarithmic scale: 255 +
// kAlphaStepsPerOctave log2(share), rounded, at least 1 (shareOfAlpha, which PartialImageBlender
// decodes, defines it and compiles the steps in). The misregistration's factor takes a node's share down to a few
// thousandths where every camera sees an edge; 8-bit linear shares that small set the nodes'
// proportions to a level or two of 255.
float shareAlpha(float share) {
  return clamp(floor(255.0 + kAlphaStepsPerOctave * log2(share) + 0.5), 1.0, 255.0) / 255.0;
}

void main() {
  float own = 0.0, unmasked = 0.0, actor = 0.0, rim = 0.0;
  vec3 rgb = vec3(0.0), rgb_rim = vec3(0.0);
  for (int j = 0; j < kOwnCameras; ++j) {
    float w = v_weight[j];
    if (w <= 0.0) continue;
    vec3 c = sampleImage(v_texel[j], j);
    if (misregistration_m > 0.0) {
      // The camera's expected error were the surface misregistration_m off along the desired ray:
      // its colour against the texels that far to either side along its shift (LumigraphParams).
      vec2 s = v_shift[j];
      float len = length(s);
      if (len > kMaxShift) s *= kMaxShift / len;
      vec3 a = sampleImage(v_texel[j] + s, j) - c, b = sampleImage(v_texel[j] - s, j) - c;
      float e2 = 0.5 * (dot(a, a) + dot(b, b));
      w /= 1.0 + e2 / (misregistration_noise * misregistration_noise);
    }
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
    colour = vec4(rgb / own, shareAlpha(own / v_total));  // a masked share stays drawn
  } else if (use_masks != 0 && (actor < kClearlyOff || rim <= 0.0)) {
    // A cell or more off the actor in every own camera (the generic mesh's foot beside the shoe, a
    // mis-posed hand): nothing of the actor is there. Discarded, it writes no depth either, so
    // the mesh behind it (the body behind the hand) or the background shows.
    discard;
  } else {
    // Just off the actor in every own camera (the cells' rim): the cameras' colours weighted by
    // their masks there (those nearest to seeing the actor count most), at a sixteenth of the share, so that a node whose cameras see the actor there outweighs it in the studio's
    // blend, and the silhouette's edge is still drawn where no camera does.
    colour = vec4(rgb_rim / rim, shareAlpha(unmasked / v_total / 16.0));
  }
}
