// The known-space file's binary fields (known_space.cpp, seen_directions.cpp), in the byte order
// of the machine (the file is a cache beside its probes, not an exchange format), each read
// checked against the bytes left. Internal to the core.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "lfprobe/error.hpp"

namespace lfprobe::known_space_bytes {

template <typename T>
void put(std::string& out, const T& value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T take(const std::string& in, std::size_t& at, const std::string& path) {
    if (at + sizeof(T) > in.size()) {
        throw InputError(path + ": the known-space file ends early (byte " + std::to_string(at) +
                         " of " + std::to_string(in.size()) + ")");
    }
    T value;
    std::memcpy(&value, in.data() + at, sizeof(T));
    at += sizeof(T);
    return value;
}

// A record count, checked against the bytes left for records of `record_bytes` each.
inline std::uint64_t take_count(const std::string& in, std::size_t& at, const std::string& path,
                                std::size_t record_bytes, const char* what) {
    const auto count = take<std::uint64_t>(in, at, path);
    if (count > (in.size() - at) / record_bytes) {
        throw InputError(path + ": the known-space file says " + std::to_string(count) + " " +
                         what + " but is shorter");
    }
    return count;
}

} // namespace lfprobe::known_space_bytes
