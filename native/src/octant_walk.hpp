// The probe walk's geometry (probe_trace.cpp): a ray's image in one octant of an octahedral map,
// where the map is a central projection, so each map coordinate is a linear-fractional function
// of the ray parameter and each texel edge is a plane through the probe centre. The walk asks
// this when it leaves a texel or a coarse cell, and where it lands after a skip; what it finds
// in the texels is the tracer's business. Internal to the core.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "texel_verdict.hpp"

namespace lfprobe::octant_walk {

using texel_verdict::kInf;

// Texel units: how far from a texel edge a map coordinate must be for its texel to be taken
// without comparing crossing times.
inline constexpr double kEdgeMargin = 1e-4;

[[nodiscard]] inline double sign_not_zero(double a) {
    return a >= 0.0 ? 1.0 : -1.0;
}

[[nodiscard]] inline int sign_of(double a) {
    return a > 0.0 ? 1 : (a < 0.0 ? -1 : 0);
}

// std::floor and std::round of a map coordinate g = (p + 1) N / 2, which lies in [0, N]: on
// baseline x86-64 both are libm calls, in the walk's every skip. For g >= 0 truncation is the
// floor, and g - floor(g) is exact (Sterbenz), so halves go up as std::round's do.
[[nodiscard]] inline int floor_of_coordinate(double g) {
    return static_cast<int>(g);
}
[[nodiscard]] inline double round_of_coordinate(double g) {
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
inline constexpr int kPieceEnd = -1;
inline constexpr int kTie = -2;
struct Event {
    int axis = kTie;
    int edge = -1;
    double lambda = 0.0;       // where along the image
    double lambda_error = 0.0; // how far off that may be
};

// The ray as every octant's piece reads it, computed once per trace.
struct MapRay {
    MapRay(const glm::dvec3& origin, const glm::dvec3& direction, int resolution)
        : o(origin), d(direction), n(resolution), two_over_n(2.0 / static_cast<double>(resolution)),
          o_l1(std::abs(origin.x) + std::abs(origin.y) + std::abs(origin.z)),
          d_l1(std::abs(direction.x) + std::abs(direction.y) + std::abs(direction.z)) {}
    glm::dvec3 o;
    glm::dvec3 d;
    int n;
    double two_over_n;
    double o_l1; // |o|_1 and |d|_1: the size of the terms of the map's coordinates
    double d_l1;
};

// One piece of the ray, [piece_start, ...], that stays in the octant of signs `s`: its two map
// coordinates and their L1-norm denominator, and where it crosses texel edges.
class OctantPiece {
public:
    OctantPiece(const MapRay& ray, const glm::dvec3& s, double piece_start)
        : n_(ray.n), two_over_n_(ray.two_over_n), o_l1_(ray.o_l1), d_l1_(ray.d_l1),
          piece_start_(piece_start) {
        const bool lower = s.z < 0.0;
        den0 = glm::dot(s, ray.o);
        den1 = glm::dot(s, ray.d);
        // Upper hemisphere: p = (x, y) / L1. Lower: p = ((x − s_x z), (y − s_y z)) / L1.
        u.num0 = ray.o.x - (lower ? s.x * ray.o.z : 0.0);
        u.num1 = ray.d.x - (lower ? s.x * ray.d.z : 0.0);
        v.num0 = ray.o.y - (lower ? s.y * ray.o.z : 0.0);
        v.num1 = ray.d.y - (lower ? s.y * ray.d.z : 0.0);
        u.step = sign_of(u.num1 * den0 - u.num0 * den1);
        v.step = sign_of(v.num1 * den0 - v.num0 * den1);
    }

    OctantCoordinate u;
    OctantCoordinate v;
    double den0 = 0.0;
    double den1 = 0.0;

    // The image's endpoints at ta and tb; not usable where the L1 norm cancels (the ray passing
    // next to the probe centre) or a coordinate moves against its step.
    [[nodiscard]] OctantImage image_of(double ta, double tb, bool order_by_image) const {
        OctantImage image;
        if (!order_by_image) {
            return image;
        }
        double gb_u = 0.0;
        double gb_v = 0.0;
        double kappa_a = 0.0;
        double kappa_b = 0.0;
        if (!image_point(ta, image.ga_u, image.ga_v, kappa_a) ||
            !image_point(tb, gb_u, gb_v, kappa_b)) {
            return image;
        }
        image.du = gb_u - image.ga_u;
        image.dv = gb_v - image.ga_v;
        // A quotient of sums of two products: a few ulps of the larger terms, which are
        // kappa times the L1 norm; in texels, times N.
        image.error = 8.0 * std::numeric_limits<double>::epsilon() * std::max(kappa_a, kappa_b) *
                      static_cast<double>(n_);
        image.usable =
            moves_with_step(u, image.du, image.inv_u) && moves_with_step(v, image.dv, image.inv_v);
        return image;
    }

    // Texel coordinates of the image at t (t = +inf: the direction's own texel), and how
    // ill-conditioned they are (the terms' magnitude over the L1 norm); false past 1e6.
    [[nodiscard]] bool image_point(double t, double& gu, double& gv, double& kappa) const {
        double den;
        double nu;
        double nv;
        double magnitude;
        if (std::isinf(t)) {
            if (t < 0.0) {
                return false;
            }
            den = den1;
            nu = u.num1;
            nv = v.num1;
            magnitude = d_l1_;
        } else {
            den = den0 + t * den1;
            nu = u.num0 + t * u.num1;
            nv = v.num0 + t * v.num1;
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
    [[nodiscard]] int land(const OctantCoordinate& c, int index, double t_exit, double g,
                           double g_error) const {
        if (c.step == 0) {
            return index;
        }
        const int guess = floor_of_coordinate(std::max(g, 0.0));
        const double from_edge = std::abs(g - round_of_coordinate(std::max(g, 0.0)));
        if (from_edge > g_error && g > 0.0 && g < static_cast<double>(n_) &&
            (c.step > 0 ? guess >= index : guess <= index)) {
            return guess;
        }
        return advance(c, index, t_exit);
    }

    // The ray parameter where coordinate `c` crosses texel edge `edge` (u or v = edge / N):
    // the plane through the probe centre with normal grad(num) − a grad(den), a = 2 edge/N − 1.
    // +inf when the ray meets that plane outside this octant (the other branch of p(t)).
    [[nodiscard]] double plane_crossing(const OctantCoordinate& c, int edge) const {
        // A product, not a quotient: exact for power-of-two N, and this is the walk's hot path.
        const double a = static_cast<double>(edge) * two_over_n_ - 1.0;
        const double denominator = c.num1 - a * den1;
        if (denominator == 0.0) {
            return kInf;
        }
        const double t = (a * den0 - c.num0) / denominator;
        // Where the L1 norm is not positive the plane is met outside this octant.
        return den0 + t * den1 > 0.0 ? t : kInf;
    }
    // The crossing as the walk sees it: an edge crossed before the piece started is behind the
    // walk already (the start index accounts for it), not ahead.
    [[nodiscard]] double crossing(const OctantCoordinate& c, int edge) const {
        const double t = plane_crossing(c, edge);
        return t < piece_start_ ? kInf : t;
    }

    // When the walk leaves texel `index` along `c` (the next edge in the step's direction).
    [[nodiscard]] double next_crossing(const OctantCoordinate& c, int index) const {
        if (c.step > 0) {
            return index + 1 < n_ ? crossing(c, index + 1) : kInf;
        }
        if (c.step < 0) {
            return index > 0 ? crossing(c, index) : kInf;
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
    [[nodiscard]] double cell_exit(const OctantCoordinate& c, int cell, int shift) const {
        const int edge = exit_edge(c, cell, shift);
        return edge >= 0 ? crossing(c, edge) : kInf;
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
    [[nodiscard]] int advance(const OctantCoordinate& c, int index, double t_exit,
                              int start = -1) const {
        if (c.step == 0) {
            return index;
        }
        if (start >= 0) {
            int guess = start;
            if (c.step > 0) {
                while (guess + 1 < n_ && crossing(c, guess + 1) <= t_exit) {
                    ++guess;
                }
            } else {
                while (guess > 0 && crossing(c, guess) <= t_exit) {
                    --guess;
                }
            }
            return guess;
        }
        const double den = den0 + t_exit * den1;
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
        const bool no_cancellation = den * 1e6 > std::abs(den0) + std::abs(t_exit * den1);
        if (from_edge > kEdgeMargin && no_cancellation &&
            (c.step > 0 ? guess >= index : guess <= index) && g > 0.0 &&
            g < static_cast<double>(n_)) {
            return guess;
        }
        if (c.step > 0) {
            guess = std::max(guess, index);
            while (guess > index && !(crossing(c, guess) <= t_exit)) {
                --guess;
            }
            while (guess + 1 < n_ && crossing(c, guess + 1) <= t_exit) {
                ++guess;
            }
        } else {
            guess = std::min(guess, index);
            while (guess < index && !(crossing(c, guess + 1) <= t_exit)) {
                ++guess;
            }
            while (guess > 0 && crossing(c, guess) <= t_exit) {
                --guess;
            }
        }
        return guess;
    }

    // The texel index of coordinate `c` at t_eval. Next to an edge the crossing time decides,
    // as the walk itself would, instead of the rounding of p.
    [[nodiscard]] int start_index(const OctantCoordinate& c, double t_eval) const {
        const double den = den0 + t_eval * den1;
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
            const double t_edge = plane_crossing(c, edge);
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

private:
    int n_;
    double two_over_n_;
    double o_l1_;
    double d_l1_;
    double piece_start_;
};

} // namespace lfprobe::octant_walk
