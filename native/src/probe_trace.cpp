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
#include "lfprobe/probe_lookup.hpp"
#include "texel_verdict.hpp"

namespace lfprobe {

using namespace texel_verdict;

namespace {

constexpr int kMaxLevels = 32;
// Texel units: how far from a texel edge a map coordinate must be for its texel to be taken
// without comparing crossing times.
constexpr double kEdgeMargin = 1e-4;

[[nodiscard]] double sign_not_zero(double a) {
    return a >= 0.0 ? 1.0 : -1.0;
}

[[nodiscard]] int sign_of(double a) {
    return a > 0.0 ? 1 : (a < 0.0 ? -1 : 0);
}

// std::floor and std::round of a map coordinate g = (p + 1) N / 2, which lies in [0, N]: on
// baseline x86-64 both are libm calls, in the walk's every skip. For g >= 0 truncation is the
// floor, and g - floor(g) is exact (Sterbenz), so halves go up as std::round's do.
[[nodiscard]] int floor_of_coordinate(double g) {
    return static_cast<int>(g);
}
[[nodiscard]] double round_of_coordinate(double g) {
    const double whole = static_cast<double>(static_cast<int>(g));
    return g - whole >= 0.5 ? whole + 1.0 : whole;
}

// One map coordinate (u or v) inside one octant, as a function of the ray parameter:
// p(t) = (num0 + t num1) / (den0 + t den1), the octahedral p = 2u − 1 of docs/DESIGN.md §3 with the
// octant's signs fixed, which makes numerator and denominator (the L1 norm) linear in t.
struct OctantCoordinate {
    double num0 = 0.0;
    double num1 = 0.0;
    int step = 0; // +1, −1: the coordinate grows or shrinks along the ray; 0: constant
};

struct OctantMap {
    OctantCoordinate u;
    OctantCoordinate v;
    double den0 = 0.0;
    double den1 = 0.0;
};

// The ray's image in the map over one piece. Inside an octant the map is a central projection,
// so the image is a straight segment: g(λ) = ga + λ (gb − ga) in texel units, λ in [0, 1] from
// the piece's start to its end (λ is a linear-fractional function of t, increasing). Which
// texel edge the walk meets first, and where the other coordinate is when it does, are then a
// multiply-add each instead of a division per edge; the times the walk keeps are still the
// exact plane crossings, and where two events are closer than the image's rounding (a texel
// corner, an edge at the piece's end) the walk compares those crossing times instead.
struct OctantImage {
    bool usable = false;
    double ga_u = 0.0;
    double ga_v = 0.0;
    double du = 0.0; // gb − ga
    double dv = 0.0;
    double inv_u = 0.0; // 1 / du; 0 for a coordinate that does not move
    double inv_v = 0.0;
    double error = 0.0; // bound on the rounding of ga and gb, texels
};

// What comes first along the image: an edge of u (axis 0) or v (axis 1), the piece's end, or
// a tie that the crossing times must settle.
constexpr int kPieceEnd = -1;
constexpr int kTie = -2;
struct Event {
    int axis = kTie;
    int edge = -1;
    double lambda = 0.0;       // where along the image
    double lambda_error = 0.0; // how far off that may be
};

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
        : map_(map), n_(map.resolution), o_(origin), d_(direction), settings_(settings) {
        b_ = glm::dot(o_, d_);
        const glm::dvec3 closest = o_ - b_ * d_;
        perp2_ = glm::dot(closest, closest);
        origin_length_ = glm::length(o_);
        texel_scale_ = thickness_per_metre(settings, n_);
        two_over_n_ = 2.0 / static_cast<double>(n_);
        o_l1_ = std::abs(o_.x) + std::abs(o_.y) + std::abs(o_.z);
        d_l1_ = std::abs(d_.x) + std::abs(d_.y) + std::abs(d_.z);
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
            near_miss_.valid = false;
            return false;
        }
        const double r = static_cast<double>(map_.distance_at(i));
        if (std::isnan(r)) {
            return stop_unknown({x, y}, t0);
        }
        if (std::isinf(r)) {
            near_miss_.valid = false;
            return false;
        }
        const double thick = thickness(r);
        if (far < r) {
            if (far >= r - thick) {
                const double t_far = distance2(t0) >= distance2(t1) ? t0 : t1;
                near_miss_ = NearMiss{true, {x, y}, i, t_far, t0};
            } else {
                near_miss_.valid = false;
            }
            return false;
        }
        const double near = min_distance(t0, t1);
        if (near > r + thick) {
            // Behind the surface the probe saw, without meeting it here.
            if (near_miss_.valid) {
                return meet(near_miss_.texel, near_miss_.index, near_miss_.t, near_miss_.t_enter);
            }
            return stop_unknown({x, y}, t0);
        }
        return meet({x, y}, i, solve_hit(r, t0, t1), t0);
    }

    // Walks the piece [ta, tb] that stays in the octant of signs `s`; true when decided.
    bool walk_piece(double ta, double tb, const glm::dvec3& s) {
        const bool lower = s.z < 0.0;
        OctantMap m;
        m.den0 = glm::dot(s, o_);
        m.den1 = glm::dot(s, d_);
        // Upper hemisphere: p = (x, y) / L1. Lower: p = ((x − s_x z), (y − s_y z)) / L1.
        m.u.num0 = o_.x - (lower ? s.x * o_.z : 0.0);
        m.u.num1 = d_.x - (lower ? s.x * d_.z : 0.0);
        m.v.num0 = o_.y - (lower ? s.y * o_.z : 0.0);
        m.v.num1 = d_.y - (lower ? s.y * d_.z : 0.0);
        m.u.step = sign_of(m.u.num1 * m.den0 - m.u.num0 * m.den1);
        m.v.step = sign_of(m.v.num1 * m.den0 - m.v.num0 * m.den1);

        piece_start_ = ta;
        int x = start_index(m, m.u, ta);
        int y = start_index(m, m.v, ta);
        double t = ta;
        const OctantImage image = image_of(m, ta, tb);

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
            const Event next = first_event(image, next_edge(m.u, x), next_edge(m.v, y));
            double t_next = kInf;
            bool step_x = false;
            bool step_y = false;
            bool decided = false;
            if (next.axis >= 0) {
                const double t_edge = crossing(m, next.axis == 0 ? m.u : m.v, next.edge);
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
                const double tnx = next_crossing(m, m.u, x);
                const double tny = next_crossing(m, m.v, y);
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
    Move skip_cell(const OctantMap& m, const OctantImage& image, double clear2, double here2,
                   int cx, int cy, int shift, int& x, int& y, double& t, double tb) {
        const Event exit = first_event(image, exit_edge(m.u, cx, shift), exit_edge(m.v, cy, shift));
        if (exit.axis == kPieceEnd) {
            const double t_end = std::max(tb, t);
            if (!skippable(clear2, here2, t_end)) {
                return Move::Stay;
            }
            if (t_end > t) {
                near_miss_.valid = false; // every texel passed was clearly in front
            }
            return Move::PieceDone;
        }
        if (exit.axis >= 0) {
            const bool along_u = exit.axis == 0;
            const OctantCoordinate& c = along_u ? m.u : m.v;
            const double t_edge = crossing(m, c, exit.edge);
            if (t_edge <= tb) {
                const double t_exit = std::max(t_edge, t);
                if (!skippable(clear2, here2, t_exit)) {
                    return Move::Stay;
                }
                // The exit axis enters the texel past the cell's edge; the other is wherever
                // the image is there, settled by crossing times when that is next to an edge.
                const int entered = exit_texel(c, along_u ? cx : cy, shift);
                if (along_u) {
                    y = land(m, m.v, y, t_exit, image.ga_v + exit.lambda * image.dv,
                             exit.lambda_error * std::abs(image.dv) + image.error);
                    x = entered;
                } else {
                    x = land(m, m.u, x, t_exit, image.ga_u + exit.lambda * image.du,
                             exit.lambda_error * std::abs(image.du) + image.error);
                    y = entered;
                }
                if (t_exit > t) {
                    near_miss_.valid = false; // every texel passed was clearly in front
                }
                t = t_exit;
                return Move::Moved;
            }
        }
        // A tie, or an image too ill-conditioned to decide: every crossing time compared.
        const double exit_x = cell_exit(m, m.u, cx, shift);
        const double exit_y = cell_exit(m, m.v, cy, shift);
        const double t_exit = std::max(std::min({exit_x, exit_y, tb}), t);
        if (!skippable(clear2, here2, t_exit)) {
            return Move::Stay;
        }
        // Along the axis whose cell edge ends the skip, the landing texel is next to that
        // edge: the search starts there.
        const int nx =
            advance(m, m.u, x, t_exit, exit_x == t_exit ? exit_texel(m.u, cx, shift) : -1);
        const int ny =
            advance(m, m.v, y, t_exit, exit_y == t_exit ? exit_texel(m.v, cy, shift) : -1);
        if (!(t_exit > t || nx != x || ny != y)) {
            return Move::Stay;
        }
        if (t_exit > t) {
            near_miss_.valid = false; // every texel passed was clearly in front
        }
        if (t_exit >= tb) {
            return Move::PieceDone;
        }
        x = nx;
        y = ny;
        t = t_exit;
        return Move::Moved;
    }

    // The image's endpoints at ta and tb; not usable where the L1 norm cancels (the ray passing
    // next to the probe centre) or a coordinate moves against its step.
    [[nodiscard]] OctantImage image_of(const OctantMap& m, double ta, double tb) const {
        OctantImage image;
        if (!settings_.order_by_image) {
            return image;
        }
        double gb_u = 0.0;
        double gb_v = 0.0;
        double kappa_a = 0.0;
        double kappa_b = 0.0;
        if (!image_point(m, ta, image.ga_u, image.ga_v, kappa_a) ||
            !image_point(m, tb, gb_u, gb_v, kappa_b)) {
            return image;
        }
        image.du = gb_u - image.ga_u;
        image.dv = gb_v - image.ga_v;
        // A quotient of sums of two products: a few ulps of the larger terms, which are
        // kappa times the L1 norm; in texels, times N.
        image.error = 8.0 * std::numeric_limits<double>::epsilon() * std::max(kappa_a, kappa_b) *
                      static_cast<double>(n_);
        image.usable = moves_with_step(m.u, image.du, image.inv_u) &&
                       moves_with_step(m.v, image.dv, image.inv_v);
        return image;
    }

    // Texel coordinates of the image at t (t = +inf: the direction's own texel), and how
    // ill-conditioned they are (the terms' magnitude over the L1 norm); false past 1e6.
    [[nodiscard]] bool image_point(const OctantMap& m, double t, double& gu, double& gv,
                                   double& kappa) const {
        double den;
        double nu;
        double nv;
        double magnitude;
        if (std::isinf(t)) {
            if (t < 0.0) {
                return false;
            }
            den = m.den1;
            nu = m.u.num1;
            nv = m.v.num1;
            magnitude = d_l1_;
        } else {
            den = m.den0 + t * m.den1;
            nu = m.u.num0 + t * m.u.num1;
            nv = m.v.num0 + t * m.v.num1;
            magnitude = o_l1_ + std::abs(t) * d_l1_;
        }
        if (!(den > 0.0) || !(den * 1e6 > magnitude)) {
            return false;
        }
        kappa = magnitude / den;
        const double half_n = 0.5 * static_cast<double>(n_);
        const double scale = half_n / den;
        gu = nu * scale + half_n;
        gv = nv * scale + half_n;
        return true;
    }

    // 1 / delta for a coordinate that moves the way the walk steps it (0 when it does not
    // step); false when the image disagrees with the step.
    [[nodiscard]] static bool moves_with_step(const OctantCoordinate& c, double delta,
                                              double& inverse) {
        inverse = 0.0;
        if (c.step == 0) {
            return true;
        }
        if (c.step > 0 ? !(delta > 0.0) : !(delta < 0.0)) {
            return false;
        }
        inverse = 1.0 / delta;
        return std::isfinite(inverse);
    }

    // The edge the walk crosses leaving texel `index` along `c`; −1 at the map's border or
    // when the coordinate does not move.
    [[nodiscard]] int next_edge(const OctantCoordinate& c, int index) const {
        if (c.step > 0) {
            return index + 1 < n_ ? index + 1 : -1;
        }
        if (c.step < 0) {
            return index > 0 ? index : -1;
        }
        return -1;
    }

    // The first of edge `eu` of u, edge `ev` of v (−1: none) and the piece's end along the
    // image; kTie when they are closer than the image's rounding or the image is not usable.
    [[nodiscard]] static Event first_event(const OctantImage& image, int eu, int ev) {
        Event event;
        if (!image.usable) {
            return event;
        }
        const double lu = eu >= 0 ? (static_cast<double>(eu) - image.ga_u) * image.inv_u : kInf;
        const double lv = ev >= 0 ? (static_cast<double>(ev) - image.ga_v) * image.inv_v : kInf;
        // An edge's λ is off by the endpoints' error over the coordinate's extent, twice.
        const double eu_error = 4.0 * image.error * std::abs(image.inv_u);
        const double ev_error = 4.0 * image.error * std::abs(image.inv_v);
        if (lu + eu_error < lv - ev_error && lu + eu_error < 1.0) {
            event = Event{0, eu, lu, eu_error};
        } else if (lv + ev_error < lu - eu_error && lv + ev_error < 1.0) {
            event = Event{1, ev, lv, ev_error};
        } else if (1.0 < lu - eu_error && 1.0 < lv - ev_error) {
            event.axis = kPieceEnd;
        }
        return event;
    }

    // The index of coordinate `c` at t_exit, given its image coordinate g there (off by at
    // most g_error): the texel under g when that is clear of every edge, else the crossing
    // times decide (advance).
    [[nodiscard]] int land(const OctantMap& m, const OctantCoordinate& c, int index, double t_exit,
                           double g, double g_error) const {
        if (c.step == 0) {
            return index;
        }
        const int guess = floor_of_coordinate(std::max(g, 0.0));
        const double from_edge = std::abs(g - round_of_coordinate(std::max(g, 0.0)));
        if (from_edge > g_error && g > 0.0 && g < static_cast<double>(n_) &&
            (c.step > 0 ? guess >= index : guess <= index)) {
            return guess;
        }
        return advance(m, c, index, t_exit);
    }

    // Passing through the ball around the probe centre, the ray forgets a surface it passed
    // just in front of: it went on past the probe.
    void pass_the_centre() { near_miss_.valid = false; }

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

    // The ray parameter where coordinate `c` crosses texel edge `edge` (u or v = edge / N):
    // the plane through the probe centre with normal grad(num) − a grad(den), a = 2 edge/N − 1.
    // +inf when the ray meets that plane outside this octant (the other branch of p(t)).
    [[nodiscard]] double plane_crossing(const OctantMap& m, const OctantCoordinate& c,
                                        int edge) const {
        // A product, not a quotient: exact for power-of-two N, and this is the walk's hot path.
        const double a = static_cast<double>(edge) * two_over_n_ - 1.0;
        const double denominator = c.num1 - a * m.den1;
        if (denominator == 0.0) {
            return kInf;
        }
        const double t = (a * m.den0 - c.num0) / denominator;
        // Where the L1 norm is not positive the plane is met outside this octant.
        return m.den0 + t * m.den1 > 0.0 ? t : kInf;
    }
    // The crossing as the walk sees it: an edge crossed before the piece started is behind the
    // walk already (the start index accounts for it), not ahead.
    [[nodiscard]] double crossing(const OctantMap& m, const OctantCoordinate& c, int edge) const {
        const double t = plane_crossing(m, c, edge);
        return t < piece_start_ ? kInf : t;
    }

    // When the walk leaves texel `index` along `c` (the next edge in the step's direction).
    [[nodiscard]] double next_crossing(const OctantMap& m, const OctantCoordinate& c,
                                       int index) const {
        if (c.step > 0) {
            return index + 1 < n_ ? crossing(m, c, index + 1) : kInf;
        }
        if (c.step < 0) {
            return index > 0 ? crossing(m, c, index) : kInf;
        }
        return kInf;
    }

    // The texel edge through which the walk leaves coarse cell `cell` (fine texels
    // [cell << shift, (cell+1) << shift)) in its step's direction; −1 when that edge is the
    // map's border or the coordinate does not move.
    [[nodiscard]] int exit_edge(const OctantCoordinate& c, int cell, int shift) const {
        if (c.step > 0) {
            const int edge = (cell + 1) << shift;
            return edge < n_ ? edge : -1;
        }
        if (c.step < 0) {
            const int edge = cell << shift;
            return edge > 0 ? edge : -1;
        }
        return -1;
    }

    // When the walk leaves coarse cell `cell` (+inf through the map's border).
    [[nodiscard]] double cell_exit(const OctantMap& m, const OctantCoordinate& c, int cell,
                                   int shift) const {
        const int edge = exit_edge(c, cell, shift);
        return edge >= 0 ? crossing(m, c, edge) : kInf;
    }

    // The texel a walk enters when it leaves coarse cell `cell` through the edge cell_exit
    // gave; −1 through the map's border (cell_exit is +inf there).
    [[nodiscard]] int exit_texel(const OctantCoordinate& c, int cell, int shift) const {
        const int edge = exit_edge(c, cell, shift);
        return edge < 0 || c.step > 0 ? edge : edge - 1;
    }

    // The fine index after every edge crossed up to t_exit: the count of edges the ray crosses
    // by then, as the fine walk's own comparisons count them, so that a skip lands exactly where
    // the fine walk would be. Crossing times grow with the edge index along the walk's
    // direction, so the search starts at the texel under p(t_exit) and settles with a few
    // comparisons instead of testing every edge a long skip passes.
    // `start`, when not −1, is a texel known to be crossed into by t_exit (exit_texel), from
    // which the search only moves on.
    [[nodiscard]] int advance(const OctantMap& m, const OctantCoordinate& c, int index,
                              double t_exit, int start = -1) const {
        if (c.step == 0) {
            return index;
        }
        if (start >= 0) {
            int guess = start;
            if (c.step > 0) {
                while (guess + 1 < n_ && crossing(m, c, guess + 1) <= t_exit) {
                    ++guess;
                }
            } else {
                while (guess > 0 && crossing(m, c, guess) <= t_exit) {
                    --guess;
                }
            }
            return guess;
        }
        const double den = m.den0 + t_exit * m.den1;
        double p = den > 0.0 ? (c.num0 + t_exit * c.num1) / den : 0.0;
        if (!std::isfinite(p)) {
            p = 0.0;
        }
        const double g = (0.5 * std::clamp(p, -1.0, 1.0) + 0.5) * static_cast<double>(n_);
        int guess = std::clamp(floor_of_coordinate(g), 0, n_ - 1);
        // Far from every edge the texel under p(t_exit) is the answer: the rounding of p and of
        // the crossing times is far below this margin, unless the L1 norm cancels (the ray
        // passing next to the probe centre). Near an edge the crossing times decide, as the
        // fine walk decides.
        const double from_edge = std::abs(g - round_of_coordinate(g));
        const bool no_cancellation = den * 1e6 > std::abs(m.den0) + std::abs(t_exit * m.den1);
        if (from_edge > kEdgeMargin && no_cancellation &&
            (c.step > 0 ? guess >= index : guess <= index) && g > 0.0 &&
            g < static_cast<double>(n_)) {
            return guess;
        }
        if (c.step > 0) {
            guess = std::max(guess, index);
            while (guess > index && !(crossing(m, c, guess) <= t_exit)) {
                --guess;
            }
            while (guess + 1 < n_ && crossing(m, c, guess + 1) <= t_exit) {
                ++guess;
            }
        } else {
            guess = std::min(guess, index);
            while (guess < index && !(crossing(m, c, guess + 1) <= t_exit)) {
                ++guess;
            }
            while (guess > 0 && crossing(m, c, guess) <= t_exit) {
                --guess;
            }
        }
        return guess;
    }

    // The texel index of coordinate `c` at t_eval. Next to an edge the crossing time decides,
    // as the walk itself would, instead of the rounding of p.
    [[nodiscard]] int start_index(const OctantMap& m, const OctantCoordinate& c,
                                  double t_eval) const {
        const double den = m.den0 + t_eval * m.den1;
        double p = den > 0.0 ? (c.num0 + t_eval * c.num1) / den : 0.0;
        if (!std::isfinite(p)) {
            p = 0.0;
        }
        p = std::clamp(p, -1.0, 1.0);
        const double g = (0.5 * p + 0.5) * static_cast<double>(n_);
        int index = std::clamp(floor_of_coordinate(g), 0, n_ - 1);
        const double nearest_edge = round_of_coordinate(g);
        const int edge = static_cast<int>(nearest_edge);
        if (c.step != 0 && std::abs(g - nearest_edge) < 1e-3 && edge > 0 && edge < n_) {
            const double t_edge = plane_crossing(m, c, edge);
            if (std::isfinite(t_edge)) {
                if (c.step > 0) {
                    index = t_edge <= t_eval ? edge : edge - 1;
                } else {
                    index = t_edge <= t_eval ? edge - 1 : edge;
                }
            }
        }
        return index;
    }

    // The squared distance from the probe below which the ray passes clearly in front of every
    // fine texel under a coarse cell of minimum distance `cell_min` (r − thickness(r) grows
    // with r since texel_scale_ < 1; less a margin that covers the rounding of the squared
    // distances compared with it): +inf for an empty cell, −1 where nothing can be passed
    // (unknown texels, or a surface within its thickness of the probe).
    [[nodiscard]] double clear2_of(double cell_min) const {
        if (std::isinf(cell_min)) {
            return kInf;
        }
        const double clear = cell_min - thickness(cell_min) - 1e-9 * (1.0 + cell_min);
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
    const TraceSettings& settings_;
    const std::vector<MinDistanceLevel>* levels_ = nullptr;
    int level_count_ = 0;
    double b_ = 0.0;
    double perp2_ = 0.0;
    double origin_length_ = 0.0;
    double texel_scale_ = 0.0;
    double two_over_n_ = 0.0;
    double o_l1_ = 0.0; // |o|_1 and |d|_1: the size of the terms of the map's coordinates
    double d_l1_ = 0.0;
    double piece_start_ = 0.0;
    NearMiss near_miss_;
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

// A probe that never saw where the ray starts answers UNKNOWN there, whatever lies beyond: the
// walk's first texel is the one around the direction to the start, and an unknown texel stops
// it. In a partial scan most probes a ray asks are such probes, and this answer costs nine
// texel reads instead of the walk's set-up and its descent through every coarse level. The
// texels around are read too, so that the texel the walk's own arithmetic picks at an edge or
// across an octant's fold is unknown as well; a start near the probe centre (where the walk
// skips the ball the probe stood in) is left to the walk. The answer is the walk's: UNKNOWN,
// proven free up to the start.
std::optional<ProbeTraceResult>
dismiss_if_unknown_at_start(const ProbeMap& map, const glm::dvec3& o, const glm::dvec3& d,
                            double t_lo, double t_hi, const TraceSettings& settings) {
    if (!settings.dismiss_unknown_start || !(t_hi > t_lo) || !std::isfinite(t_lo)) {
        return std::nullopt;
    }
    const glm::dvec3 start = o + t_lo * d;
    const double length = glm::length(start);
    if (!(length > 2.0 * settings.eye_at_probe_distance) || !std::isfinite(length)) {
        return std::nullopt;
    }
    const int n = map.resolution;
    const oct::Texel home = oct::texel_of_direction(glm::vec3(start / length), n);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const oct::Texel t = oct::wrap_texel(home.x + dx, home.y + dy, n);
            if (!std::isnan(map.distance_at(oct::texel_index(t, n)))) {
                return std::nullopt;
            }
        }
    }
    ProbeTraceResult result;
    set_unknown(result, home, t_lo);
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
            dismiss_if_unknown_at_start(map, o, d, t_lo, t_hi, settings)) {
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
