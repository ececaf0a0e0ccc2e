// What a baked probe is good for (issue "model only what a scene needs"): a probe inside
// geometry sees mostly the backs of surfaces, a probe pressed against a wall sees half its
// sphere at a few millimetres, a probe outside the data sees nothing. Such probes are moved
// (within a bounded distance, as DDGI relocates its probes) or dropped instead of being stored
// at full resolution. Back faces are told by the stored normals, which scans orient toward the
// scanner that saw the point.
#pragma once

#include <cstdint>
#include <limits>

#include <glm/vec3.hpp>

#include "lfprobe/probe_map.hpp"

namespace lfprobe {

enum class ProbeClass : std::uint8_t {
    Useful = 0,   // sees surfaces from their front, at a distance
    Inside = 1,   // most surfaces it sees face away from it: it is inside an object
    TooClose = 2, // part of its sphere sees a surface nearer than the clearance
    Blind = 3,    // almost nothing measured around it (outside the scanned space)
    Idle = 4,     // no surface within its cell's reach: its neighbours answer for it
};

[[nodiscard]] const char* probe_class_name(ProbeClass c);

struct ClassificationSettings {
    double inside_back_face_fraction = 0.5; // of the surface texels
    double clearance = 0.05;                // metres
    double too_close_fraction = 0.01;       // of all texels nearer than the clearance
    double blind_surface_fraction = 0.05;   // surface texels below this fraction: blind
    double cell_reach = std::numeric_limits<double>::infinity(); // Idle beyond this (metres)
};

struct ProbeClassification {
    ProbeClass kind = ProbeClass::Useful;
    double surface_fraction = 0.0;   // of all texels: measured or inferred surface
    double back_face_fraction = 0.0; // of the surface texels
    double near_fraction = 0.0;      // of all texels: surface nearer than the clearance
    double unknown_fraction = 0.0;
    double empty_fraction = 0.0;
    double nearest_surface = std::numeric_limits<double>::infinity(); // metres
    // Unit direction toward the nearest surface (Inside: the way out; TooClose: the wall);
    // zero when the probe sees no surface.
    glm::dvec3 toward_nearest{0.0};
    // Unit direction toward the open side: the mean direction of the farther surface texels
    // minus that of the near ones; zero when none is near.
    glm::dvec3 away_from_near{0.0};
    // Unit direction toward what the probe sees: the mean direction of its measured texels
    // (surface or empty) minus that of its unknown ones; zero when none is unknown.
    glm::dvec3 toward_known{0.0};
};

[[nodiscard]] ProbeClassification classify_probe(const ProbeMap& map,
                                                 const ClassificationSettings& settings = {});

} // namespace lfprobe
