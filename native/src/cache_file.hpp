// Writing a cache entry (scan_cache.cpp, prepared_cloud_cache.cpp, spatial_cloud.cpp): every
// byte written or an IoError, to a temporary that is removed unless the rename made it the
// entry, so an interrupted or failed write never leaves a partial entry; and what an entry read
// back must hold. Internal to the core.
#pragma once

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <string>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace lfprobe::cache_file {

// Whether every component of a vector read from an entry is finite: an entry is checked before
// it is used, and a range check written as `x < limit` lets a NaN through.
[[nodiscard]] inline bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// A normal as the core stores one: finite, unit length or zero (no normal known); the margin
// takes the rounding of a normalised float vector.
[[nodiscard]] inline bool plausible_normal(const glm::vec3& n) {
    return finite(n) && glm::dot(n, n) <= 1.01f;
}

// Writes all of `size` bytes to `fd` or throws IoError naming `name`.
void write_all(int fd, const void* data, std::size_t size, const std::string& name);

// A temporary beside `entry` (ENTRY.tmp.PID.N), removed on destruction unless committed.
class TemporaryFile {
public:
    explicit TemporaryFile(const std::filesystem::path& entry);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;
    [[nodiscard]] const std::filesystem::path& path() const { return path_; }
    // Renames the temporary to `entry`; from then on it is no longer removed.
    void commit_as(const std::filesystem::path& entry);

private:
    std::filesystem::path path_;
    bool committed_ = false;
};

// Creates `path` for writing (it must not exist); throws IoError.
[[nodiscard]] int create_for_writing(const std::string& path);

// Closes `fd`, throwing IoError when the data could not be written.
void close_written(int fd, const std::string& name);

} // namespace lfprobe::cache_file
