#include "lfprobe/render.hpp"

#include <algorithm>
#include <chrono>
#include <vector>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "lfprobe/error.hpp"

namespace lfprobe {

nlohmann::json RenderStats::to_json() const {
    return nlohmann::json{{"rays", rays},
                          {"hits", hits},
                          {"misses", misses},
                          {"unknown", unknown},
                          {"steps", steps},
                          {"probes_tried", probes_tried},
                          {"seconds", seconds},
                          {"rays_per_second", rays_per_second()},
                          {"mean_steps", mean_steps()},
                          {"mean_probes", mean_probes()}};
}

nlohmann::json render_settings_json(const RenderSettings& settings) {
    const TraceSettings& p = settings.trace.probe;
    return nlohmann::json{{"mode", field_mode_name(settings.trace.mode)},
                          {"max_probes", settings.trace.max_probes},
                          {"thickness", p.thickness},
                          {"thickness_texels", p.thickness_texels},
                          {"use_coarse_levels", p.use_coarse_levels},
                          {"eye_at_probe_distance", p.eye_at_probe_distance},
                          {"tile_size", settings.tile_size},
                          {"sample", {settings.sample_x, settings.sample_y}}};
}

namespace {

// The probe the eye sits at (within the trace's eye-at-probe distance), or -1.
int probe_at(const ProbeField& field, const glm::dvec3& eye, const TraceSettings& settings) {
    for (std::size_t i = 0; i < field.probe_count(); ++i) {
        if (glm::length(eye - field.probe(i).position) <= settings.eye_at_probe_distance) {
            return static_cast<int>(i);
        }
    }
    return -1;
}

// The eye probe's O(1) lookup, falling back to the whole field where it answers UNKNOWN.
// Every camera ray starts at the eye, so the lookup needs no walk set-up at all.
FieldTraceResult trace_from_eye_probe(const ProbeField& field, int eye_probe, const Ray& ray,
                                      const FieldTraceSettings& settings) {
    const ProbeTraceResult r =
        field.lookup_one(static_cast<std::size_t>(eye_probe), ray, settings.probe);
    if (r.status == TraceStatus::Unknown) {
        return field.trace(ray, settings);
    }
    FieldTraceResult result;
    result.status = r.status;
    result.t = r.t;
    result.free_until = r.free_until;
    result.radiance = r.radiance;
    result.normal = r.normal;
    result.probe = eye_probe;
    result.texel = r.texel;
    result.steps = r.steps();
    result.probes_tried = 1;
    return result;
}

// One camera ray through the field: the eye probe's lookup when the eye sits at a probe.
FieldTraceResult trace_camera_ray(const ProbeField& field, int eye_probe, const Ray& ray,
                                  const FieldTraceSettings& settings) {
    return eye_probe >= 0 ? trace_from_eye_probe(field, eye_probe, ray, settings)
                          : field.trace(ray, settings);
}

} // namespace

ThroughputResult probe_trace_throughput(const ProbeField& field, const Camera& camera,
                                        const RenderSettings& settings, int repeats) {
    FieldTraceSettings trace = settings.trace;
    trace.mode = field.resolve_mode(settings.trace);
    const glm::dvec3 offset = field.world_offset();
    const int eye_probe = probe_at(field, camera.position() - offset, trace.probe);
    return measure_throughput(camera, offset, repeats, "probe trace", [&](const Ray& ray) {
        return trace_camera_ray(field, eye_probe, ray, trace).status == TraceStatus::Hit;
    });
}

RenderedImage render_probe_view(const ProbeField& field, const Camera& camera,
                                const RenderSettings& settings, Progress* progress,
                                RenderStats* stats) {
    if (settings.tile_size < 1) {
        throw InputError("render: tile_size must be at least 1");
    }
    // Resolve the mode once, so that a bad request fails before any work.
    FieldTraceSettings trace = settings.trace;
    trace.mode = field.resolve_mode(settings.trace);
    RenderedImage image(camera.width, camera.height);
    // Probe traces per pixel, summed after the parallel loop (no shared counters).
    std::vector<std::uint32_t> probes_tried(image.pixel_count(), 0);
    if (progress != nullptr) {
        progress->begin_stage("tracing", image.pixel_count());
    }
    const auto start = std::chrono::steady_clock::now();
    const glm::dvec3 offset = field.world_offset();
    const std::size_t tile = static_cast<std::size_t>(settings.tile_size);
    // An eye at a probe (DESIGN.md §4): every ray is one texel lookup in that probe; only rays
    // it cannot answer (UNKNOWN texels) go through the whole field.
    const int eye_probe = probe_at(field, camera.position() - offset, trace.probe);
    const CameraRays camera_rays(camera);
    tbb::parallel_for(
        tbb::blocked_range2d<int>(0, camera.height, tile, 0, camera.width, tile),
        [&](const tbb::blocked_range2d<int>& r) {
            if (progress != nullptr) {
                progress->throw_if_cancelled();
            }
            for (int y = r.rows().begin(); y < r.rows().end(); ++y) {
                for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                    const Ray ray = camera_rays.local_pixel_ray(x, y, offset, settings.sample_x,
                                                                settings.sample_y);
                    const FieldTraceResult hit = trace_camera_ray(field, eye_probe, ray, trace);
                    const std::size_t i = image.index(x, y);
                    const bool is_hit = hit.status == TraceStatus::Hit;
                    if (is_hit) {
                        image.rgba[4 * i] = hit.radiance.x;
                        image.rgba[4 * i + 1] = hit.radiance.y;
                        image.rgba[4 * i + 2] = hit.radiance.z;
                        image.rgba[4 * i + 3] = 1.0f;
                        image.depth[i] = static_cast<float>(hit.t);
                        image.normal[3 * i] = hit.normal.x;
                        image.normal[3 * i + 1] = hit.normal.y;
                        image.normal[3 * i + 2] = hit.normal.z;
                    }
                    image.status[i] = static_cast<std::uint8_t>(hit.status);
                    image.probe[i] = hit.probe;
                    image.steps[i] = hit.steps;
                    probes_tried[i] = hit.probes_tried;
                }
            }
            if (progress != nullptr) {
                progress->advance(r.rows().size() * r.cols().size());
            }
        },
        tbb::simple_partitioner());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (stats != nullptr) {
        *stats = stats_of(image);
        stats->seconds = seconds;
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
    }
    return s;
}

RenderStats render_probe_view_to_exr(const std::string& folder, const std::string& camera_path,
                                     const std::string& output_path, const RenderSettings& settings,
                                     Progress* progress) {
    const Camera camera = read_camera_json(camera_path);
    const ProbeField field = ProbeField::load(folder, progress);
    RenderStats stats;
    const RenderedImage image = render_probe_view(field, camera, settings, progress, &stats);
    const nlohmann::json metadata{
        {"renderer", "lfprobe probe trace"},
        {"probe_set", folder},
        {"camera", camera.to_json()},
        {"settings", render_settings_json(settings)},
        {"resolved_mode", field_mode_name(field.resolve_mode(settings.trace))},
        {"stats", stats.to_json()}};
    write_rendered_exr(output_path, image, metadata.dump());
    return stats;
}

} // namespace lfprobe
