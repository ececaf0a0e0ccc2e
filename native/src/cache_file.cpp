#include "cache_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#include "lfprobe/error.hpp"

namespace lfprobe::cache_file {

namespace fs = std::filesystem;

void write_all(int fd, const void* data, std::size_t size, const std::string& name) {
    const auto* bytes = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t written = ::write(fd, bytes, size);
        if (written < 0) {
            if (errno == EINTR) {
                continue;
            }
            throw IoError(name + ": cannot write (" + std::strerror(errno) + ")");
        }
        bytes += written;
        size -= static_cast<std::size_t>(written);
    }
}

TemporaryFile::TemporaryFile(const fs::path& entry) {
    static std::atomic<std::uint64_t> counter{0};
    path_ = entry.string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

TemporaryFile::~TemporaryFile() {
    if (!committed_) {
        std::error_code ignored;
        fs::remove(path_, ignored);
    }
}

void TemporaryFile::commit_as(const fs::path& entry) {
    fs::rename(path_, entry);
    committed_ = true;
}

int create_for_writing(const std::string& path) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
        throw IoError(path + ": cannot create (" + std::strerror(errno) + ")");
    }
    return fd;
}

void close_written(int fd, const std::string& name) {
    if (::close(fd) != 0) {
        throw IoError(name + ": cannot write (" + std::strerror(errno) + ")");
    }
}

} // namespace lfprobe::cache_file
