#include "lfprobe/seen_directions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "known_space_bytes.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/octahedral.hpp"
#include "start_dismissal.hpp"

namespace lfprobe {

using namespace known_space_bytes;

namespace {

constexpr float kNone = -std::numeric_limits<float>::infinity();

std::size_t word_count(int n) {
    return (static_cast<std::size_t>(n) * static_cast<std::size_t>(n) + 63) / 64;
}

} // namespace

SeenDirections::SeenDirections(const ProbeMap& map)
    : resolution_(map.resolution),
      block_(std::max(1, (map.resolution + kBlocksPerSide - 1) / kBlocksPerSide)),
      blocks_((map.resolution + block_ - 1) / block_), known_(word_count(map.resolution), 0),
      farthest_(static_cast<std::size_t>(blocks_) * static_cast<std::size_t>(blocks_), kNone) {
    const int n = resolution_;
    for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
            const std::size_t i = oct::texel_index({x, y}, n);
            const float d = map.distance_at(i);
            if (std::isnan(d)) {
                continue;
            }
            known_[i >> 6] |= std::uint64_t{1} << (i & 63);
            float& far = farthest_[block_of(x, y)];
            far = std::max(far, d);
        }
    }
}

bool SeenDirections::dismisses(const Ray& ray, const TraceSettings& settings, double slack) const {
    const int n = resolution_;
    if (n <= 0) {
        return false;
    }
    const std::optional<start_dismissal::Start> start =
        start_dismissal::dismissible_start(ray, n, settings);
    if (!start) {
        return false;
    }
    // First the blocks the nine texels lie in (4 KiB a probe, where the bits take 32 KiB): the
    // farthest known distance of any of them bounds each texel's. Most starts a partial scan's
    // probes are asked about lie in blocks that know nothing, or behind all they know.
    const int x = start->home.x;
    const int y = start->home.y;
    if (x >= 1 && y >= 1 && x + 1 < n && y + 1 < n) { // no texel wraps
        float farthest = kNone;
        for (const int by : {(y - 1) / block_, (y + 1) / block_}) {
            for (const int bx : {(x - 1) / block_, (x + 1) / block_}) {
                farthest = std::max(farthest, farthest_[static_cast<std::size_t>(by) * blocks_ +
                                                        static_cast<std::size_t>(bx)]);
            }
        }
        if (farthest == kNone || start_dismissal::behind_beyond_reach(
                                     *start, n, settings, static_cast<double>(farthest) + slack)) {
            return true;
        }
    }
    // Then texel by texel: each known texel bounded by its own block's farthest.
    return start_dismissal::stops_at_first_texel(*start, n, settings, [&](oct::Texel t) {
        const std::size_t i = oct::texel_index(t, n);
        if (((known_[i >> 6] >> (i & 63)) & 1U) == 0) {
            return std::numeric_limits<double>::quiet_NaN();
        }
        return static_cast<double>(farthest_[block_of(t.x, t.y)]) + slack;
    });
}

void SeenDirections::write_to(std::string& out) const {
    put(out, static_cast<std::int32_t>(resolution_));
    for (const std::uint64_t word : known_) {
        put(out, word);
    }
    for (const float far : farthest_) {
        put(out, far);
    }
}

SeenDirections SeenDirections::read_from(const std::string& in, std::size_t& at,
                                         const std::string& path) {
    const auto n = take<std::int32_t>(in, at, path);
    if (!(n >= 1 && n <= kMaxProbeResolution)) {
        throw InputError(path + ": a probe's resolution in the known-space file is " +
                         std::to_string(n) + ", expected 1 to " +
                         std::to_string(kMaxProbeResolution));
    }
    SeenDirections seen;
    seen.resolution_ = n;
    seen.block_ = std::max(1, (n + kBlocksPerSide - 1) / kBlocksPerSide);
    seen.blocks_ = (n + seen.block_ - 1) / seen.block_;
    seen.known_.resize(word_count(n));
    seen.farthest_.resize(static_cast<std::size_t>(seen.blocks_) *
                          static_cast<std::size_t>(seen.blocks_));
    const std::size_t bytes =
        seen.known_.size() * sizeof(std::uint64_t) + seen.farthest_.size() * sizeof(float);
    if (bytes > in.size() - std::min(at, in.size())) {
        throw InputError(path + ": the known-space file ends inside a probe's known directions");
    }
    for (std::uint64_t& word : seen.known_) {
        word = take<std::uint64_t>(in, at, path);
    }
    for (float& far : seen.farthest_) {
        far = take<float>(in, at, path);
        // A bound: -inf (none known), a distance, or +inf (an empty texel's); never NaN.
        if (std::isnan(far) || (std::isfinite(far) && far < 0.0f)) {
            throw InputError(path +
                             ": a probe's farthest known distance in the known-space "
                             "file is " +
                             std::to_string(far));
        }
    }
    return seen;
}

} // namespace lfprobe
