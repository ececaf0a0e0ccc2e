// Test folders and files: a fresh, empty folder under GoogleTest's temporary directory per test,
// and whole-file reads and writes.
#pragma once

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

namespace lfprobe::testing {

// An empty folder `prefix` + `name` under the test run's temporary directory (emptied first).
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
    const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / (prefix + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

inline std::string file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_file(const std::filesystem::path& path, const std::string& content) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
}

} // namespace lfprobe::testing
