#include "lfprobe/rendered_image.hpp"

#include <limits>

namespace lfprobe {

RenderedImage::RenderedImage(int w, int h)
    : width(w), height(h), rgba(pixel_count() * 4, 0.0f),
      depth(pixel_count(), std::numeric_limits<float>::infinity()), normal(pixel_count() * 3, 0.0f),
      status(pixel_count(), 0), probe(pixel_count(), -1), steps(pixel_count(), 0) {}

} // namespace lfprobe
