// Filling a rendered view's narrow holes: the samples of a probe render that ended UNKNOWN (no
// probe could say what the ray meets) are given a colour inferred from the HIT colour of the
// pixels around them, as a bake fills a probe's narrow holes from the texels around them
// (docs/DESIGN.md §5 "Holes in a view"). The status plane keeps saying UNKNOWN, so the hole rate
// and the magenta of the report's pictures are unchanged; only the colour a viewer sees is.
#pragma once

#include <cstdint>
#include <span>

#include "lfprobe/rendered_image.hpp"

namespace lfprobe {

// The widest hole a render fills unless told otherwise: 5 % of the image's larger side (32
// pixels at 640), at least 2. Wider regions of UNKNOWN pixels stay black: a partial scan's
// unscanned side is shown as what it is, not smeared over.
[[nodiscard]] int default_hole_fill_pixels(int width, int height);

struct UnknownFillStats {
    std::uint64_t pixels_filled = 0; // pixels with no HIT sample that were given a colour
    std::uint64_t pixels_left = 0;   // pixels with no HIT sample in holes too wide to fill
};

// For every pixel i with unknown_share[i] > 0 (the share of its samples that ended UNKNOWN):
// its colour gains unknown_share[i] × the fill colour and its coverage unknown_share[i], where
// the fill colour is a pull-push (a mip pyramid of the HIT colour weighted by coverage, pushed
// back down with bilinear interpolation) of the pixels around it. A pixel with no HIT sample
// is filled only when its 8-connected region of such pixels lies within ceil(max_width / 2)
// pixels of a pixel with a HIT: holes at most max_width pixels across. A hole on a silhouette
// (the depths on its border differ by over 5 % of the nearest) is a disocclusion, what no
// probe saw behind the near surface: it is filled from its far border alone (the pixels at
// least as far as the middle of its border's depths), layer by layer inward, then blended to
// the harmonic interpolation of that border, as a probe's disocclusions are, instead of by the
// pull-push. max_width 0 fills nothing. Deterministic: the
// same image and shares give the same result on any thread count.
UnknownFillStats fill_unknown_pixels(RenderedImage& image, std::span<const float> unknown_share,
                                     int max_width);

} // namespace lfprobe
