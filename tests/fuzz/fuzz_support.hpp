// What every libFuzzer harness shares: a scratch folder of its own (on tmpfs where there is one,
// so an execution costs no disk I/O), files written there from the fuzzer's bytes, and checks
// that stop the run (a crash libFuzzer records, with the input) when a reader returns a value it
// promises never to return.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <string_view>

#include <tbb/global_control.h>
#include <unistd.h>

namespace lfprobe::fuzz {

// One thread: an execution is deterministic, and two harnesses running side by side (tools/
// fuzz.sh --jobs 2) do not fight over the cores with TBB's idle workers.
inline const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

// The harness's folder, made once per process: /dev/shm/lfprobe-fuzz-PID (or under TMPDIR).
inline const std::filesystem::path& scratch_folder() {
    static const std::filesystem::path folder = [] {
        std::filesystem::path base = "/dev/shm";
        if (!std::filesystem::is_directory(base)) {
            const char* tmp = std::getenv("TMPDIR");
            base = tmp != nullptr ? tmp : "/tmp";
        }
        std::filesystem::path made = base / ("lfprobe-fuzz-" + std::to_string(::getpid()));
        std::filesystem::create_directories(made);
        // Removed when the process ends normally; libFuzzer ends a run with exit().
        std::atexit([] {
            std::error_code ignored;
            std::filesystem::remove_all(scratch_folder(), ignored);
        });
        return made;
    }();
    return folder;
}

// Writes `bytes` to `name` in the scratch folder (replacing it) and returns its path. A file
// whose bytes are those of its last write is left as it is: a harness writing several files
// per input (an OBJ, its MTL, a texture) mostly sees one of them change.
inline std::string write_scratch_file(const std::string& name, std::string_view bytes) {
    const std::filesystem::path path = scratch_folder() / name;
    static std::map<std::string, std::string> last_written;
    const auto last = last_written.find(name);
    if (last != last_written.end() && last->second == bytes) {
        return path.string();
    }
    last_written[name] = std::string(bytes);
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
        std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
        std::abort();
    }
    return path.string();
}

// The whole of the file at `path` (empty when it cannot be read).
inline std::string file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Splits `bytes` at the first `separator`: the part before it, and the rest (empty when absent).
inline std::pair<std::string_view, std::string_view> split_at(std::string_view bytes,
                                                              std::string_view separator) {
    const std::size_t at = bytes.find(separator);
    if (at == std::string_view::npos) {
        return {bytes, {}};
    }
    return {bytes.substr(0, at), bytes.substr(at + separator.size())};
}

// The cache harnesses' input, written over the cache entry at `entry_path`: with the first
// byte odd the rest goes through `structured` (which gives it a header whose checksum matches),
// else the rest is the entry as it is. False for an empty input.
template <class Structured>
bool write_cache_entry(const std::uint8_t* data, std::size_t size, const std::string& entry_path,
                       Structured&& structured) {
    if (size == 0) {
        return false;
    }
    const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
    const std::string entry = (data[0] & 1) != 0 ? structured(rest) : std::string(rest);
    std::ofstream out(entry_path, std::ios::binary | std::ios::trunc);
    out.write(entry.data(), static_cast<std::streamsize>(entry.size()));
    return true;
}

// A broken promise of the code under test: print it and abort, which libFuzzer reports as a
// crash and saves the input for.
[[noreturn]] inline void broken_promise(const char* what) {
    std::fprintf(stderr, "fuzz harness: %s\n", what);
    std::abort();
}

inline void expect(bool condition, const char* what) {
    if (!condition) {
        broken_promise(what);
    }
}

} // namespace lfprobe::fuzz
