// Errors that carry where bad input was found, so that Python users see the file, the line
// (or byte offset) and what was expected instead of a bare message.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace lfprobe {

// Bad input (a malformed file, an impossible parameter). Mapped to Python's ValueError.
class InputError : public std::runtime_error {
public:
    explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// Where in a file an InputError points; line is 1-based, 0 when the format has no lines.
struct FileLocation {
    std::string path;
    std::uint64_t line = 0;
    std::uint64_t byte_offset = 0;
    bool has_line = false;
};

// "path:line: what" or "path: byte offset N: what".
[[nodiscard]] InputError input_error_at(const FileLocation& where, const std::string& what);

// A file that could not be opened, read or written. Mapped to Python's OSError.
class IoError : public std::runtime_error {
public:
    explicit IoError(const std::string& message) : std::runtime_error(message) {}
};

// An input file that is not there, or is not a regular file (a folder, a FIFO, a device): bad
// input, as a malformed file is. Mapped to Python's FileNotFoundError (and NativeIOError), so
// the command line exits 2 for it as for every other bad input.
class MissingFileError : public IoError {
public:
    explicit MissingFileError(const std::string& message) : IoError(message) {}
};

// Work stopped because the user asked (Esc in Blender, Ctrl-C). Mapped to KeyboardInterrupt.
class Cancelled : public std::runtime_error {
public:
    Cancelled() : std::runtime_error("cancelled") {}
};

} // namespace lfprobe
