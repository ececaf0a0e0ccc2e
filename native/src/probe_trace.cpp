#include "lfprobe/probe_trace.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "lfprobe/enum_names.hpp"
#include "lfprobe/error.hpp"
#include "lfprobe/min_distance_pyramid.hpp"
#include "lfprobe/probe_lookup.hpp"
#include "octant_walk.hpp"
#include "start_dismissal.hpp"
#include "texel_verdict.hpp"

namespace lfprobe {

using namespace texel_verdict;
using namespace octant_walk;

namespace {

constexpr int kMaxLevels = 32;

// A texel the ray passed just in front of (within the thickness): the hit if the ray then
// turns up behind the next surface.
struct NearMiss {
    bool valid = false;
    oct::Texel texel;
    std::size_t index = 0;
    double t = 0.0;
    double t_enter = 0.0;
};

class Tracer {
public:
    Tracer(const ProbeMap& map, const MinDistancePyramid* levels, const glm::dvec3& origin,
           const glm::dvec3& direction, const TraceSettings& settings)
        : map_(map), n_(map.resolution), o_(origin), d_(direction),
          ray_(origin, direction, map.resolution), settings_(settings) {
        b_ = glm::dot(o_, d_);
        const glm::dvec3 closest = o_ - b_ * d_;
        perp2_ = glm::dot(closest, closest);
        origin_length_ = glm::length(o_);
        texel_scale_ = thickness_per_metre(settings, n_);
        if (levels != nullptr && settings.use_coarse_levels && texel_scale_ < 1.0) {
            levels_ = &levels->levels();
            level_count_ = std::min(static_cast<int>(levels_->size()), kMaxLevels);
        }
    }

    // Judges fine texel (x, y) over the ray interval [t0, t1]; true when the trace is decided.
    bool visit_texel(int x, int y, double t0, double t1) {
        if (!(t1 > t0)) {
            return false; // the ray only touches the texel at a point
        }
        ++result_.fine_steps;
        const std::size_t i = oct::texel_index({x, y}, n_);
        const double far = max_distance(t0, t1);
        if (far <= settings_.eye_at_probe_distance) {
            // Within this ball around the probe centre nothing can be: the probe stood there.
            forget_near_misses();
            return false;
        }
        const double r = static_cast<double>(map_.distance_at(i));
        if (std::isnan(r)) {
            return stop_unknown({x, y}, t0);
        }
        if (std::isinf(r)) {
            forget_near_misses();
            return false;
        }
        const double thick = thickness(r);
        const double wide = fallback_thickness(r);
        if (far < r) {
            const double t_far = distance2(t0) >= distance2(t1) ? t0 : t1;
            const NearMiss passed{true, {x, y}, i, t_far, t0};
            near_miss_ = far >= r - thick ? passed : NearMiss{};
            wide_miss_ = far >= r - wide ? passed : NearMiss{};
            return false;
        }
        const double near = min_distance(t0, t1);
        if (near > r + thick) {
            // Behind the surface the probe saw, without meeting it here.
            if (near_miss_.valid) {
                return meet(near_miss_.texel, near_miss_.index, near_miss_.t, near_miss_.t_enter);
            }
            stop_unknown({x, y}, t0);
            if (wide_miss_.valid) {
                keep_fallback(wide_miss_.texel, wide_miss_.index, wide_miss_.t);
            } else if (near <= r + wide) {
                keep_fallback({x, y}, i, solve_hit(r, t0, t1));
            }
            return true;
        }
        return meet({x, y}, i, solve_hit(r, t0, t1), t0);
    }

    // Walks the piece [ta, tb] that stays in the octant of signs `s`; true when decided.
    bool walk_piece(double ta, double tb, const glm::dvec3& s) {
        const OctantPiece m(ray_, s, ta);
        int x = m.start_index(m.u, ta);
        int y = m.start_index(m.v, ta);
        double t = ta;
        const OctantImage image = m.image_of(ta, tb, settings_.order_by_image);

        std::array<int, kMaxLevels> memo_x;
        std::array<int, kMaxLevels> memo_y;
        memo_x.fill(-1);
        memo_y.fill(-1);

        // Hierarchical walk in the manner of Hi-Z tracing: test the coarse cell around the
        // current texel; skip it whole when nothing in it can stop the ray and try the next
        // coarser level, otherwise descend; after a fine texel, start again at the finest level.
        // A piece starts at the coarsest level: a cell the ray is already too far for is
        // dismissed by one read and one comparison, before its exit is sought.
        // Cells found not skippable are remembered so that they are not tested again.
        const int top = level_count_ - 1;
        int level = top;
        double here2 = distance2(t); // the ray's squared distance from the probe at t
        // A piece that starts on an unknown texel, or too near or behind its own texel's
        // surface to pass it, can skip no cell around it: every coarse cell that holds the
        // texel bounds no farther than the texel does (clear2_of grows with the distance), so
        // the descent would test each level only to find that. Go to the texel at once, each
        // level's cell remembered as tested. (Most of a partial scan's re-asked probes stop
        // there: on the real pump-room scan a quarter of all probe traces.)
        if (top >= 0) {
            const double home = static_cast<double>(
                min_distance_bound(map_.distance_at(oct::texel_index({x, y}, n_))));
            if (!(here2 < clear2_of(home))) {
                for (int l = 0; l <= top; ++l) {
                    memo_x[static_cast<std::size_t>(l)] = x >> (l + 1);
                    memo_y[static_cast<std::size_t>(l)] = y >> (l + 1);
                }
                level = -1;
            }
        }
        const long max_iterations = 16L * n_ + 64L * (level_count_ + 1);
        for (long iteration = 0; iteration < max_iterations; ++iteration) {
            if (level >= 0) {
                const std::size_t l = static_cast<std::size_t>(level);
                const int shift = level + 1;
                const int cx = x >> shift;
                const int cy = y >> shift;
                if (memo_x[l] == cx && memo_y[l] == cy) {
                    --level;
                    continue;
                }
                ++result_.coarse_steps;
                const MinDistanceLevel& lv = (*levels_)[l];
                const double cell_min = static_cast<double>(lv.value(
                    static_cast<std::size_t>(cy) * static_cast<std::size_t>(lv.resolution) +
                    static_cast<std::size_t>(cx)));
                const double clear2 = clear2_of(cell_min);
                if (here2 < clear2) {
                    const Move move =
                        skip_cell(m, image, clear2, here2, cx, cy, shift, x, y, t, tb);
                    if (move == Move::PieceDone) {
                        return false;
                    }
                    if (move == Move::Moved) {
                        here2 = distance2(t);
                        level = std::min(level + 1, top);
                        continue;
                    }
                }
                memo_x[l] = cx;
                memo_y[l] = cy;
                --level;
                continue;
            }
            // The texel's exit: the first of its two forward edges and the piece's end.
            const Event next =
                OctantPiece::first_event(image, m.next_edge(m.u, x), m.next_edge(m.v, y));
            double t_next = kInf;
            bool step_x = false;
            bool step_y = false;
            bool decided = false;
            if (next.axis >= 0) {
                const double t_edge = m.crossing(next.axis == 0 ? m.u : m.v, next.edge);
                if (t_edge <= tb) {
                    t_next = std::max(t_edge, t);
                    step_x = next.axis == 0;
                    step_y = next.axis == 1;
                    decided = true;
                }
            } else if (next.axis == kPieceEnd) {
                t_next = std::max(tb, t);
                decided = true;
            }
            if (!decided) {
                const double tnx = m.next_crossing(m.u, x);
                const double tny = m.next_crossing(m.v, y);
                t_next = std::max(std::min({tnx, tny, tb}), t);
                step_x = tnx <= t_next;
                step_y = tny <= t_next;
            }
            if (visit_texel(x, y, t, t_next)) {
                return true;
            }
            if (t_next >= tb) {
                return false;
            }
            if (step_x) {
                x += m.u.step;
            }
            if (step_y) {
                y += m.v.step;
            }
            t = t_next;
            here2 = distance2(t);
            level = top >= 0 ? 0 : -1;
        }
        // Unreachable for a monotone walk; a guard against looping on corrupt input.
        return stop_unknown({x, y}, t);
    }

    // What a coarse step did: moved past the cell, ended the piece inside it, or neither.
    enum class Move { Moved, PieceDone, Stay };

    // Skips coarse cell (cx, cy) of `shift` (2^shift texels a side) when nothing in it can stop
    // the ray, moving (x, y, t) to where the fine walk would be when it leaves the cell.
    // The ray is at squared distance here2 from the probe at t; clear2 is the cell's clear2_of.
    Move skip_cell(const OctantPiece& m, const OctantImage& image, double clear2, double here2,
                   int cx, int cy, int shift, int& x, int& y, double& t, double tb) {
        const Event exit = OctantPiece::first_event(image, m.exit_edge(m.u, cx, shift),
                                                    m.exit_edge(m.v, cy, shift));
        if (exit.axis == kPieceEnd) {
            const double t_end = std::max(tb, t);
            if (!skippable(clear2, here2, t_end)) {
                return Move::Stay;
            }
            if (t_end > t) {
                forget_near_misses(); // every texel passed was clearly in front
            }
            return Move::PieceDone;
        }
        if (exit.axis >= 0) {
            const bool along_u = exit.axis == 0;
            const OctantCoordinate& c = along_u ? m.u : m.v;
            const double t_edge = m.crossing(c, exit.edge);
            if (t_edge <= tb) {
                const double t_exit = std::max(t_edge, t);
                if (!skippable(clear2, here2, t_exit)) {
                    return Move::Stay;
                }
                // The exit axis enters the texel past the cell's edge; the other is wherever
                // the image is there, settled by crossing times when that is next to an edge.
                const int entered = m.exit_texel(c, along_u ? cx : cy, shift);
                if (along_u) {
                    y = m.land(m.v, y, t_exit, image.ga_v + exit.lambda * image.dv,
                               exit.lambda_error * std::abs(image.dv) + image.error);
                    x = entered;
                } else {
                    x = m.land(m.u, x, t_exit, image.ga_u + exit.lambda * image.du,
                               exit.lambda_error * std::abs(image.du) + image.error);
                    y = entered;
                }
                if (t_exit > t) {
                    forget_near_misses(); // every texel passed was clearly in front
                }
                t = t_exit;
                return Move::Moved;
            }
        }
        // A tie, or an image too ill-conditioned to decide: every crossing time compared.
        const double exit_x = m.cell_exit(m.u, cx, shift);
        const double exit_y = m.cell_exit(m.v, cy, shift);
        const double t_exit = std::max(std::min({exit_x, exit_y, tb}), t);
        if (!skippable(clear2, here2, t_exit)) {
            return Move::Stay;
        }
        // Along the axis whose cell edge ends the skip, the landing texel is next to that
        // edge: the search starts there.
        const int nx =
            m.advance(m.u, x, t_exit, exit_x == t_exit ? m.exit_texel(m.u, cx, shift) : -1);
        const int ny =
            m.advance(m.v, y, t_exit, exit_y == t_exit ? m.exit_texel(m.v, cy, shift) : -1);
        if (!(t_exit > t || nx != x || ny != y)) {
            return Move::Stay;
        }
        if (t_exit > t) {
            forget_near_misses(); // every texel passed was clearly in front
        }
        if (t_exit >= tb) {
            return Move::PieceDone;
        }
        x = nx;
        y = ny;
        t = t_exit;
        return Move::Moved;
    }

    // Passing through the ball around the probe centre, the ray forgets a surface it passed
    // just in front of: it went on past the probe.
    void pass_the_centre() { forget_near_misses(); }

    void finish_miss(double t_max) { set_miss(result_, t_max); }

    [[nodiscard]] const ProbeTraceResult& result() const { return result_; }

private:
    // |o + t d|², written around the closest approach so that it does not cancel near it.
    [[nodiscard]] double distance2(double t) const {
        const double along = t + b_;
        return perp2_ + along * along;
    }
    [[nodiscard]] double max_distance(double t0, double t1) const {
        if (!std::isfinite(t1)) {
            return kInf;
        }
        return std::sqrt(std::max(distance2(t0), distance2(t1)));
    }
    [[nodiscard]] double min_distance(double t0, double t1) const {
        return std::sqrt(distance2(std::clamp(-b_, t0, t1)));
    }
    [[nodiscard]] double thickness(double r) const {
        return settings_.thickness + texel_scale_ * r;
    }
    // The fallback's reach (TraceSettings::fallback_thickness), never less than the thickness.
    [[nodiscard]] double fallback_thickness(double r) const {
        return std::max(settings_.fallback_thickness, settings_.thickness) + texel_scale_ * r;
    }

    void forget_near_misses() {
        near_miss_.valid = false;
        wide_miss_.valid = false;
    }

    // The UNKNOWN just set keeps the surface of texel `index`, met at t, as its fallback when
    // the surface faces the ray (a back face is no answer, as for a HIT).
    void keep_fallback(oct::Texel texel, std::size_t index, double t) {
        const glm::vec3 normal = map_.normal_at(index);
        if (glm::dot(glm::dvec3(normal), d_) > 0.0 || !std::isfinite(t)) {
            return;
        }
        result_.has_fallback = true;
        result_.t_fallback = t;
        result_.fallback_texel = texel;
        result_.radiance = map_.radiance_at(index);
        result_.normal = normal;
    }

    // The squared distance from the probe below which the ray passes clearly in front of every
    // fine texel under a coarse cell of minimum distance `cell_min`, the fallback's reach
    // included, so that a skip never passes a surface the fallback would keep (r − reach(r)
    // grows with r since texel_scale_ < 1; less a margin that covers the rounding of the
    // squared distances compared with it): +inf for an empty cell, −1 where nothing can be
    // passed (unknown texels, or a surface within its reach of the probe).
    [[nodiscard]] double clear2_of(double cell_min) const {
        if (std::isinf(cell_min)) {
            return kInf;
        }
        const double clear = cell_min - fallback_thickness(cell_min) - 1e-9 * (1.0 + cell_min);
        return clear > 0.0 ? clear * clear : -1.0;
    }

    // True when no fine texel under a cell of squared clear distance `clear2` can stop the ray
    // over [t, t1], the ray at squared distance `here2` at t: each is empty or clearly behind
    // the ray, whose largest distance is at an end.
    [[nodiscard]] bool skippable(double clear2, double here2, double t1) const {
        if (std::isinf(clear2)) {
            return true;
        }
        if (!std::isfinite(t1)) {
            return false;
        }
        return std::max(here2, distance2(t1)) < clear2;
    }

    // The first t in [t0, t1] with |o + t d| = r (t² + 2bt + c = 0, stable form), or, when
    // the ray only comes within the thickness, the t where it comes closest to r.
    [[nodiscard]] double solve_hit(double r, double t0, double t1) const {
        const double p = std::sqrt(perp2_);
        const double disc = (r - p) * (r + p);
        double best = kInf;
        if (disc >= 0.0) {
            const double s = std::sqrt(disc);
            const double q = -(b_ + (b_ >= 0.0 ? s : -s));
            const double c = (origin_length_ - r) * (origin_length_ + r);
            const double root_a = q;
            const double root_b = q != 0.0 ? c / q : -b_;
            for (const double root : {std::min(root_a, root_b), std::max(root_a, root_b)}) {
                if (root >= t0 && root <= t1) {
                    best = root;
                    break;
                }
            }
        }
        if (std::isfinite(best)) {
            return best;
        }
        double best_error = kInf;
        for (const double t : {t0, std::clamp(-b_, t0, t1), t1}) {
            if (!std::isfinite(t)) {
                continue;
            }
            const double error = std::abs(std::sqrt(distance2(t)) - r);
            if (error < best_error) {
                best_error = error;
                best = t;
            }
        }
        return best;
    }

    bool meet(oct::Texel texel, std::size_t index, double t, double t_enter) {
        meet_texel(map_, index, texel, d_, t, t_enter, result_);
        return true;
    }

    bool stop_unknown(oct::Texel texel, double t_enter) {
        set_unknown(result_, texel, t_enter);
        return true;
    }

    const ProbeMap& map_;
    int n_;
    glm::dvec3 o_;
    glm::dvec3 d_;
    MapRay ray_;
    const TraceSettings& settings_;
    const std::vector<MinDistanceLevel>* levels_ = nullptr;
    int level_count_ = 0;
    double b_ = 0.0;
    double perp2_ = 0.0;
    double origin_length_ = 0.0;
    double texel_scale_ = 0.0;
    NearMiss near_miss_;
    NearMiss wide_miss_; // as near_miss_, within the fallback thickness
    ProbeTraceResult result_;
};

} // namespace

const char* trace_status_name(TraceStatus status) {
    static constexpr auto names = std::to_array<EnumName<TraceStatus>>({
        {TraceStatus::Miss, "MISS"},
        {TraceStatus::Hit, "HIT"},
        {TraceStatus::Unknown, "UNKNOWN"},
    });
    return name_of(names, status);
}

double surface_thickness(const TraceSettings& settings, double distance, int n) {
    return settings.thickness + thickness_per_metre(settings, n) * distance;
}

namespace {

// A probe that never saw where the ray starts answers UNKNOWN there, whatever lies beyond
// (start_dismissal.hpp). In a partial scan most probes a ray asks are such probes, and this
// answer costs nine texel reads instead of the walk's set-up and its descent through every
// coarse level. The answer is the walk's: UNKNOWN, proven free up to the start.
std::optional<ProbeTraceResult> dismiss_if_unknown_at_start(const ProbeMap& map, const Ray& ray,
                                                            const TraceSettings& settings) {
    const int n = map.resolution;
    const std::optional<start_dismissal::Start> start =
        start_dismissal::dismissible_start(ray, n, settings);
    if (!start || !start_dismissal::stops_at_first_texel(*start, n, settings, [&](oct::Texel t) {
            return static_cast<double>(map.distance_at(oct::texel_index(t, n)));
        })) {
        return std::nullopt;
    }
    ProbeTraceResult result;
    set_unknown(result, start->home, start->t_lo);
    result.fine_steps = 1; // the texel that stopped it, as the walk counts it; no descent
    return result;
}

} // namespace

ProbeTraceResult trace_probe(const ProbeMap& map, const MinDistancePyramid* levels, const Ray& ray,
                             const TraceSettings& settings) {
    const glm::dvec3& o = ray.origin;
    if (glm::length(o) <= settings.eye_at_probe_distance) {
        // The lookup checks the map and the direction itself.
        return ProbeLookup(map, settings).lookup(ray.direction, ray.t_min, ray.t_max);
    }
    check_inputs(map, ray.direction);
    const glm::dvec3 d = glm::normalize(ray.direction);
    const double t_lo = ray.t_min;
    const double t_hi = ray.t_max;
    if (std::optional<ProbeTraceResult> dismissed =
            dismiss_if_unknown_at_start(map, ray, settings)) {
        return *dismissed;
    }
    Tracer tracer(map, levels, o, d, settings);
    if (!(t_hi > t_lo)) {
        tracer.finish_miss(t_hi);
        return tracer.result();
    }
    // Where the ray crosses the probe's axis planes: the octant boundaries.
    // The ball of radius eye_at_probe_distance around the centre, where directions from the
    // centre are undefined: the walk resumes after it with the texel of the position there.
    const double ball_radius = settings.eye_at_probe_distance;
    const glm::dvec3 closest = o - glm::dot(o, d) * d;
    const double perp2 = glm::dot(closest, closest);
    double ball_in = kInf;
    double ball_out = kInf;
    if (perp2 < ball_radius * ball_radius) {
        const double half = std::sqrt(ball_radius * ball_radius - perp2);
        ball_in = -glm::dot(o, d) - half;
        ball_out = -glm::dot(o, d) + half;
    }
    std::array<double, 3> plane_t{kInf, kInf, kInf};
    std::array<double, 5> cuts{};
    std::size_t cut_count = 0;
    cuts[cut_count++] = t_lo;
    for (int axis = 0; axis < 3; ++axis) {
        if (d[axis] != 0.0) {
            plane_t[static_cast<std::size_t>(axis)] = -o[axis] / d[axis];
            const double t = plane_t[static_cast<std::size_t>(axis)];
            if (t > t_lo && t < t_hi) {
                cuts[cut_count++] = t;
            }
        }
    }
    // At most three inner cuts: an insertion sort.
    for (std::size_t i = 2; i < cut_count; ++i) {
        for (std::size_t j = i; j > 1 && cuts[j] < cuts[j - 1]; --j) {
            std::swap(cuts[j], cuts[j - 1]);
        }
    }
    cuts[cut_count++] = t_hi;
    for (std::size_t piece = 0; piece + 1 < cut_count; ++piece) {
        const double ta = cuts[piece];
        const double tb = cuts[piece + 1];
        if (!(tb > ta)) {
            continue;
        }
        const double t_mid = std::isfinite(tb) ? ta + 0.5 * (tb - ta) : ta + 1.0 + std::abs(ta);
        glm::dvec3 signs;
        for (int axis = 0; axis < 3; ++axis) {
            if (d[axis] == 0.0) {
                signs[axis] = sign_not_zero(o[axis]);
            } else {
                const double side = t_mid > plane_t[static_cast<std::size_t>(axis)] ? 1.0 : -1.0;
                signs[axis] = side * (d[axis] > 0.0 ? 1.0 : -1.0);
            }
        }
        const double before_ball = std::min(tb, ball_in);
        if (before_ball > ta && tracer.walk_piece(ta, before_ball, signs)) {
            return tracer.result();
        }
        const double after_ball = std::max(ta, ball_out);
        if (after_ball < tb) {
            if (after_ball > ta) {
                tracer.pass_the_centre();
            }
            if (tracer.walk_piece(after_ball, tb, signs)) {
                return tracer.result();
            }
        }
    }
    tracer.finish_miss(t_hi);
    return tracer.result();
}

} // namespace lfprobe
