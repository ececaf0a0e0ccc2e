#include "lfprobe/render.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "lfprobe/error.hpp"
#include "lfprobe/image_exr.hpp"
#include "lfprobe/image_metadata.hpp"
#include "lfprobe/image_tiles.hpp"
#include "lfprobe/probe_blend.hpp"
#include "lfprobe/probe_lookup.hpp"
#include "lfprobe/radiance_filter.hpp"
#include "lfprobe/unknown_fill.hpp"

namespace lfprobe {

nlohmann::json RenderStats::to_json() const {
    return nlohmann::json{{"rays", rays},
                          {"hits", hits},
                          {"misses", misses},
                          {"unknown", unknown},
                          {"steps", steps},
                          {"probes_tried", probes_tried},
                          {"holes_filled", holes_filled},
                          {"holes_left", holes_left},
                          {"guessed", guessed},
                          {"seconds", seconds},
                          {"rays_per_second", rays_per_second()},
                          {"mean_steps", mean_steps()},
                          {"mean_probes", mean_probes()}};
}

nlohmann::json render_settings_json(const RenderSettings& settings) {
    const TraceSettings& p = settings.trace.probe;
    return nlohmann::json{
        {"mode", field_mode_name(settings.trace.mode)},
        {"max_probes", settings.trace.max_probes},
        {"thickness", p.thickness},
        {"fallback_thickness", p.fallback_thickness},
        {"max_probes_per_ray", settings.trace.max_probes_per_ray},
        {"stop_where_no_probe_can_answer", settings.trace.stop_where_no_probe_can_answer},
        {"thickness_texels", p.thickness_texels},
        {"use_coarse_levels", p.use_coarse_levels},
        {"eye_at_probe_distance", p.eye_at_probe_distance},
        {"filter", radiance_filter_name(settings.trace.filter)},
        {"blend", settings.trace.blend},
        {"prefer_measured", settings.trace.prefer_measured},
        {"samples_per_pixel", settings.samples_per_pixel},
        {"hole_fill_pixels", settings.hole_fill_pixels},
        {"tile_size", settings.tile_size},
        {"sample", {settings.sample_x, settings.sample_y}}};
}

namespace {

// The probe the eye sits at (within the trace's eye-at-probe distance), or -1.
int probe_at(const ProbeField& field, const glm::dvec3& eye, const TraceSettings& settings) {
    for (std::size_t i = 0; i < field.probe_count(); ++i) {
        if (glm::length(eye - field.probe_position(i)) <= settings.eye_at_probe_distance) {
            return static_cast<int>(i);
        }
    }
    return -1;
}

// Where a view's rays go first: the lookup of the probe the eye sits at, if it sits at one,
// with the per-probe work done once per view.
struct EyeProbe {
    int index = -1;
    std::optional<ProbeLookup> lookup;

    EyeProbe(const ProbeField& field, const glm::dvec3& eye, const TraceSettings& settings)
        : index(probe_at(field, eye, settings)) {
        if (index >= 0) {
            lookup.emplace(field.probe(static_cast<std::size_t>(index)), settings);
        }
    }
};

// Camera rays traced together, so that the eye probe's lookups fetch their texels together.
constexpr std::size_t kRayBatch = 2 * ProbeLookup::kBatch;

// The eye probe's answer as the field's, written field by field: a batch's results are not
// copied through temporaries.
void set_from_eye_probe(FieldTraceResult& result, const ProbeTraceResult& r, int probe) {
    result.status = r.status;
    result.t = r.t;
    result.free_until = r.free_until;
    result.radiance = r.radiance;
    result.normal = r.normal;
    result.probe = probe;
    result.texel = r.texel;
    result.steps = r.steps();
    result.probes_tried = 1;
}

// How a view's camera rays are traced, set up once per view: the trace mode resolved (a bad
// request fails before any work) and the probe the eye sits at found. The image, the
// throughput figure and its floor all trace through it, so they trace alike.
class ViewTracer {
public:
    ViewTracer(const ProbeField& field, const Camera& camera, const RenderSettings& settings)
        : field_(field), trace_(settings.trace),
          eye_(field, camera.position() - field.world_offset(), settings.trace.probe) {
        trace_.mode = field.resolve_mode(settings.trace);
        if (settings.trace.blend < 1 || settings.trace.blend > 8) {
            throw InputError("render: blend must be in [1, 8] probes, got " +
                             std::to_string(settings.trace.blend));
        }
    }

    // Traces camera rays[0, count), count at most kRayBatch, into hits[0, count). From an eye
    // at a probe every ray is that probe's O(1) lookup, and only the rays it answers UNKNOWN go
    // through the whole field; every camera ray starts at the eye, so the lookup needs no walk
    // set-up.
    void trace_batch(const Ray* rays, std::size_t count, FieldTraceResult* hits) const {
        if (eye_.index < 0) {
            for (std::size_t k = 0; k < count; ++k) {
                hits[k] = field_.trace(rays[k], trace_);
            }
            return;
        }
        std::array<ProbeTraceResult, kRayBatch> answers;
        eye_.lookup->lookup_batch(rays, count, answers.data());
        for (std::size_t k = 0; k < count; ++k) {
            if (answers[k].status == TraceStatus::Unknown) {
                hits[k] = field_.trace(rays[k], trace_);
            } else {
                if (trace_.filter != RadianceFilter::Nearest) {
                    refine_at_edge(rays[k], answers[k]);
                }
                set_from_eye_probe(hits[k], answers[k], eye_.index);
                if (trace_.filter != RadianceFilter::Nearest &&
                    answers[k].status == TraceStatus::Hit) {
                    // The eye probe alone: from its centre no other probe adds detail.
                    const auto probe = static_cast<std::size_t>(eye_.index);
                    const ProbeMap& map = field_.probe(probe);
                    // From the probe's centre the eye and the probe are equally far.
                    const RadianceFootprint footprint =
                        footprint_of(field_, probe, answers[k].t, answers[k].t, trace_);
                    hits[k].radiance = filtered_radiance(
                        map, rays[k].direction, answers[k].texel,
                        surface_thickness(trace_.probe, answers[k].t, map.resolution),
                        trace_.filter, footprint);
                }
            }
        }
    }

    // The eye probe's answer judged again on the texel whose surface holds most of the
    // bilinear weight around the ray (majority_surface_texel), where that is another texel: the
    // filters read the colour at the ray's exact direction, and this reads the surface there
    // too. Nearest keeps the paper's texel.
    void refine_at_edge(const Ray& ray, ProbeTraceResult& answer) const {
        if (answer.status != TraceStatus::Hit && answer.status != TraceStatus::Miss) {
            return;
        }
        const oct::Texel met =
            answer.status == TraceStatus::Hit ? answer.texel : eye_texel(ray.direction);
        const ProbeMap& map = field_.probe(static_cast<std::size_t>(eye_.index));
        const double distance =
            static_cast<double>(map.distance_at(oct::texel_index(met, map.resolution)));
        if (std::isnan(distance)) {
            return;
        }
        const double tolerance = std::isfinite(distance)
                                     ? surface_thickness(trace_.probe, distance, map.resolution)
                                     : 0.0;
        const oct::Texel seen = majority_surface_texel(map, ray.direction, met, tolerance);
        if (seen.x != met.x || seen.y != met.y) {
            const ProbeTraceResult other =
                eye_.lookup->lookup_texel(ray.direction, seen, ray.t_min, ray.t_max);
            if (other.status != TraceStatus::Unknown) {
                answer = other;
            }
        }
    }

    [[nodiscard]] oct::Texel eye_texel(const glm::dvec3& direction) const {
        const ProbeMap& map = field_.probe(static_cast<std::size_t>(eye_.index));
        return oct::texel_of_direction(glm::vec3(glm::normalize(direction)), map.resolution);
    }

    // Traces rays[0, count), any count, a batch at a time, calling each(k, answer of ray k).
    template <class Each>
    void trace(const Ray* rays, std::size_t count, Each&& each) const {
        std::array<FieldTraceResult, kRayBatch> hits;
        for (std::size_t first = 0; first < count; first += kRayBatch) {
            const std::size_t size = std::min(kRayBatch, count - first);
            trace_batch(rays + first, size, hits.data());
            for (std::size_t k = 0; k < size; ++k) {
                each(first + k, hits[k]);
            }
        }
    }

private:
    const ProbeField& field_;
    FieldTraceSettings trace_;
    EyeProbe eye_;
};

// The camera's rays in the field's frame, each moved to start where its trace ended
// (rays_started_at_answers).
std::vector<Ray> rays_started_at_answers(const ViewTracer& tracer, const Camera& camera,
                                         const glm::dvec3& offset) {
    std::vector<Ray> rays = camera_local_rays(camera, offset);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, rays.size(), kRayBatch),
        [&](const tbb::blocked_range<std::size_t>& r) {
            Ray* first = rays.data() + r.begin();
            tracer.trace(first, r.size(), [&](std::size_t k, const FieldTraceResult& h) {
                const double end = h.status == TraceStatus::Hit ? h.t : h.free_until;
                if (h.status != TraceStatus::Miss && std::isfinite(end)) {
                    first[k].t_min = std::max(first[k].t_min, end);
                }
            });
        });
    return rays;
}

} // namespace

std::vector<Ray> rays_started_at_answers(const ProbeField& field, const Camera& camera,
                                         const RenderSettings& settings) {
    return rays_started_at_answers(ViewTracer(field, camera, settings), camera,
                                   field.world_offset());
}

ThroughputResult probe_trace_throughput(const ProbeField& field, const Camera& camera,
                                        const RenderSettings& settings, int repeats,
                                        ThroughputStart start) {
    if (repeats < 1) {
        throw InputError("probe trace throughput: repeats must be at least 1");
    }
    const ViewTracer tracer(field, camera, settings);
    const glm::dvec3 offset = field.world_offset();
    const std::vector<Ray> rays = start == ThroughputStart::Answer
                                      ? rays_started_at_answers(tracer, camera, offset)
                                      : camera_local_rays(camera, offset);
    return measure_rays_throughput(
        rays, repeats, "probe trace", [&](const Ray* batch, std::size_t count) {
            std::uint64_t hit_count = 0;
            tracer.trace(batch, count, [&](std::size_t, const FieldTraceResult& h) {
                hit_count += h.status == TraceStatus::Hit ? 1 : 0;
            });
            return hit_count;
        });
}

namespace {

// Writes a HIT's surface (depth, normal) and the pixel's status, probe and steps.
void set_centre(RenderedImage& image, std::size_t i, const FieldTraceResult& hit) {
    if (hit.status == TraceStatus::Hit) {
        image.depth[i] = static_cast<float>(hit.t);
        image.normal[3 * i] = hit.normal.x;
        image.normal[3 * i + 1] = hit.normal.y;
        image.normal[3 * i + 2] = hit.normal.z;
    }
    image.status[i] = static_cast<std::uint8_t>(hit.status);
    image.probe[i] = hit.probe;
    image.steps[i] = hit.steps;
}

void set_colour(RenderedImage& image, std::size_t i, const glm::vec3& colour, float coverage) {
    image.rgba[4 * i] = colour.x;
    image.rgba[4 * i + 1] = colour.y;
    image.rgba[4 * i + 2] = colour.z;
    image.rgba[4 * i + 3] = coverage;
}

// The mean colour of a pixel's samples, kept as differences from the first HIT so that a
// surface of one colour gives exactly that colour, and the count of HITs.
struct SampleMean {
    glm::vec3 first{0.0f};
    glm::vec3 sum{0.0f};
    int hits = 0;
    int unknown = 0;

    void add(const FieldTraceResult& h) {
        if (h.status != TraceStatus::Hit) {
            unknown += h.status == TraceStatus::Unknown ? 1 : 0;
            return;
        }
        if (hits == 0) {
            first = h.radiance;
        } else {
            sum += h.radiance - first;
        }
        ++hits;
    }
    // Premultiplied by coverage, as the ground truth's colour is.
    [[nodiscard]] glm::vec3 colour(int samples) const {
        if (hits == 0) {
            return glm::vec3{0.0f};
        }
        const glm::vec3 mean = first + sum / static_cast<float>(hits);
        return hits == samples ? mean
                               : mean * (static_cast<float>(hits) / static_cast<float>(samples));
    }
};

// The footprint filter's width: the angle one of the n × n samples of a pixel spans at the image
// centre, unless the settings give one.
RenderSettings with_sample_angle(const RenderSettings& settings, const Camera& camera, int n) {
    RenderSettings s = settings;
    if (s.trace.filter == RadianceFilter::Footprint && s.trace.sample_angle <= 0.0) {
        const double pixel_angle =
            camera.type == CameraType::Perspective
                ? 1.0 / camera.pixels_per_tangent()
                : (camera.longitude_max - camera.longitude_min) / static_cast<double>(camera.width);
        s.trace.sample_angle = pixel_angle / static_cast<double>(n);
    }
    return s;
}

} // namespace

namespace {

// Settings come from users (the CLI, the add-on, scripts): a NaN or negative thickness would
// silently answer every ray as a miss or a hit.
void require_valid_trace_settings(const RenderSettings& settings) {
    const TraceSettings& t = settings.trace.probe;
    if (!std::isfinite(t.thickness) || t.thickness < 0.0) {
        throw InputError("render: thickness must be a finite number of metres, 0 or more (got " +
                         std::to_string(t.thickness) + ")");
    }
    if (!std::isfinite(t.fallback_thickness) || t.fallback_thickness < 0.0) {
        throw InputError(
            "render: fallback_thickness must be a finite number of metres, 0 or more (got " +
            std::to_string(t.fallback_thickness) + ")");
    }
    if (settings.trace.max_probes_per_ray < 0) {
        throw InputError("render: max_probes_per_ray must be 0 (no bound) or more (got " +
                         std::to_string(settings.trace.max_probes_per_ray) + ")");
    }
    if (!std::isfinite(t.thickness_texels) || t.thickness_texels < 0.0) {
        throw InputError("render: thickness_texels must be a finite number, 0 or more (got " +
                         std::to_string(t.thickness_texels) + ")");
    }
    if (!(settings.sample_x >= 0.0 && settings.sample_x <= 1.0 && settings.sample_y >= 0.0 &&
          settings.sample_y <= 1.0)) {
        throw InputError("render: the sample position must lie in the pixel (0 to 1)");
    }
    if (settings.hole_fill_pixels < -1) {
        throw InputError("render: hole_fill_pixels must be -1 (the default width), 0 (off) or a "
                         "width in pixels (got " +
                         std::to_string(settings.hole_fill_pixels) + ")");
    }
}

} // namespace

RenderedImage render_probe_view(const ProbeField& field, const Camera& camera,
                                const RenderSettings& settings, Progress* progress,
                                RenderStats* stats) {
    if (settings.tile_size < 1) {
        throw InputError("render: tile_size must be at least 1");
    }
    require_valid_trace_settings(settings);
    const int n = samples_per_axis(settings.samples_per_pixel, "render");
    // An eye at a probe (docs/DESIGN.md §4): every ray is one texel lookup in that probe; only rays
    // it cannot answer (UNKNOWN texels) go through the whole field.
    const ViewTracer tracer(field, camera, with_sample_angle(settings, camera, n));
    RenderedImage image(camera.width, camera.height);
    image.guessed.assign(image.pixel_count(), 0);
    // Probe traces per pixel, summed after the parallel loop (no shared counters).
    std::vector<std::uint32_t> probes_tried(image.pixel_count(), 0);
    // The share of each pixel's samples that ended UNKNOWN: what the hole fill colours.
    std::vector<float> unknown_share(image.pixel_count(), 0.0f);
    if (progress != nullptr) {
        progress->begin_stage("tracing", image.pixel_count());
    }
    const glm::dvec3 offset = field.world_offset();
    const CameraRays camera_rays(camera);
    camera_rays.require_finite_rays();
    // With an odd n the middle stratum is the pixel centre: its ray is the centre's.
    const int middle = n % 2 == 1 ? n / 2 : -1;
    const bool centre_is_sample =
        middle >= 0 && settings.sample_x == 0.5 && settings.sample_y == 0.5;
    const double seconds = for_each_image_tile(
        camera.width, camera.height, settings.tile_size, progress, [&](const ImageTile& r) {
            std::array<Ray, kRayBatch> rays;
            std::array<FieldTraceResult, kRayBatch> hits;
            std::vector<Ray> sample_rays;
            for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
                for (int x0 = r.cols().begin(); x0 < r.cols().end();) {
                    const int count = std::min(static_cast<int>(kRayBatch), r.cols().end() - x0);
                    const std::size_t size = static_cast<std::size_t>(count);
                    for (int k = 0; k < count; ++k) {
                        rays[static_cast<std::size_t>(k)] = camera_rays.local_pixel_ray(
                            x0 + k, y, offset, settings.sample_x, settings.sample_y);
                    }
                    tracer.trace_batch(rays.data(), size, hits.data());
                    for (int k = 0; k < count; ++k) {
                        const FieldTraceResult& hit = hits[static_cast<std::size_t>(k)];
                        const std::size_t i = image.index(x0 + k, y);
                        set_centre(image, i, hit);
                        image.guessed[i] =
                            hit.status == TraceStatus::Hit && hit.probe >= 0 &&
                                    field.is_inferred(static_cast<std::size_t>(hit.probe),
                                                      hit.texel)
                                ? 1
                                : 0;
                        probes_tried[i] = hit.probes_tried;
                        if (n == 1) {
                            if (hit.status == TraceStatus::Hit) {
                                set_colour(image, i, hit.radiance, 1.0f);
                            }
                            unknown_share[i] = hit.status == TraceStatus::Unknown ? 1.0f : 0.0f;
                            continue;
                        }
                        // The n×n strata of the pixel, in the ground truth's order.
                        SampleMean mean;
                        sample_rays.clear();
                        for (int sy = 0; sy < n; ++sy) {
                            for (int sx = 0; sx < n; ++sx) {
                                if (centre_is_sample && sx == middle && sy == middle) {
                                    sample_rays.push_back(Ray{}); // placeholder: the centre
                                    continue;
                                }
                                sample_rays.push_back(camera_rays.local_pixel_ray(
                                    x0 + k, y, offset, stratum_centre(sx, n),
                                    stratum_centre(sy, n)));
                            }
                        }
                        const std::size_t centre_slot =
                            centre_is_sample ? static_cast<std::size_t>(middle * n + middle)
                                             : sample_rays.size();
                        std::uint32_t steps = hit.steps;
                        std::uint32_t tried = hit.probes_tried;
                        std::size_t slot = 0;
                        auto each = [&](std::size_t, const FieldTraceResult& h) {
                            if (slot == centre_slot) {
                                mean.add(hit);
                                ++slot;
                            }
                            mean.add(h);
                            steps += h.steps;
                            tried += h.probes_tried;
                            ++slot;
                        };
                        if (centre_is_sample) {
                            // Trace the strata before and after the centre, in order.
                            tracer.trace(sample_rays.data(), centre_slot, each);
                            tracer.trace(sample_rays.data() + centre_slot + 1,
                                         sample_rays.size() - centre_slot - 1, each);
                            if (slot == centre_slot) {
                                mean.add(hit); // the centre was the last stratum
                            }
                        } else {
                            tracer.trace(sample_rays.data(), sample_rays.size(), each);
                        }
                        const int samples = n * n;
                        set_colour(image, i, mean.colour(samples),
                                   static_cast<float>(mean.hits) / static_cast<float>(samples));
                        unknown_share[i] =
                            static_cast<float>(mean.unknown) / static_cast<float>(samples);
                        image.steps[i] = steps;
                        probes_tried[i] = tried;
                    }
                    x0 += count;
                }
            }
        });
    // The holes filled after every pixel is traced (a fill reads the pixels around a hole);
    // its time is part of the frame's.
    const auto fill_start = std::chrono::steady_clock::now();
    const int fill_width = settings.hole_fill_pixels < 0
                               ? default_hole_fill_pixels(camera.width, camera.height)
                               : settings.hole_fill_pixels;
    const UnknownFillStats filled = fill_unknown_pixels(image, unknown_share, fill_width);
    const double fill_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - fill_start).count();
    if (stats != nullptr) {
        *stats = stats_of(image);
        stats->seconds = seconds + fill_seconds;
        stats->holes_filled = filled.pixels_filled;
        stats->holes_left = filled.pixels_left;
        const std::uint64_t per_pixel =
            static_cast<std::uint64_t>(n * n) + (n > 1 && !centre_is_sample ? 1 : 0);
        stats->rays = image.pixel_count() * per_pixel;
        for (const std::uint32_t count : probes_tried) {
            stats->probes_tried += count;
        }
    }
    return image;
}

RenderStats stats_of(const RenderedImage& image) {
    RenderStats s;
    s.rays = image.pixel_count();
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
        switch (static_cast<TraceStatus>(image.status[i])) {
        case TraceStatus::Hit:
            ++s.hits;
            break;
        case TraceStatus::Miss:
            ++s.misses;
            break;
        case TraceStatus::Unknown:
            ++s.unknown;
            break;
        }
        s.steps += image.steps[i];
        s.guessed += image.guessed.empty() ? 0 : image.guessed[i];
    }
    return s;
}

ImageMetadata probe_view_metadata(const ProbeField& field, const Camera& camera,
                                  const RenderSettings& settings, const RenderStats& stats) {
    ImageMetadata m;
    m.renderer = "lfprobe probe trace";
    m.source =
        nlohmann::json{{"probes", field.folder()},
                       {"storage", field.storage().to_json()},
                       {"memory_bytes", field.memory_bytes()},
                       {"resolved_mode", field_mode_name(field.resolve_mode(settings.trace))}};
    m.camera = camera.to_json();
    m.settings = render_settings_json(settings);
    m.stats = stats.to_json();
    return m;
}

RenderedImage render_probe_view_to_exr(const ProbeField& field, const Camera& camera,
                                       const RenderSettings& settings,
                                       const std::string& output_path, Progress* progress,
                                       RenderStats* stats) {
    RenderStats own;
    RenderStats& s = stats != nullptr ? *stats : own;
    RenderedImage image = render_probe_view(field, camera, settings, progress, &s);
    if (!output_path.empty()) {
        write_rendered_exr(output_path, image, probe_view_metadata(field, camera, settings, s));
    }
    return image;
}

RenderStats render_probe_set_to_exr(const std::string& folder, const Camera& camera,
                                    const RenderSettings& settings,
                                    const std::optional<ProbeStorage>& storage,
                                    const std::string& output_path, Progress* progress) {
    if (progress != nullptr) {
        progress->begin_stage("loading probes", 1);
    }
    const ProbeField field = ProbeField::load(folder, progress, 0, storage);
    RenderStats stats;
    (void)render_probe_view_to_exr(field, camera, settings, output_path, progress, &stats);
    return stats;
}

} // namespace lfprobe
