// Read-only mmap of a file, released on destruction.
#include "lfprobe/mapped_file.hpp"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

[[noreturn]] void throw_system_error(const std::string& path, const char* action, int error) {
    const std::string message = path + ": cannot " + action + " (" + std::strerror(error) + ")";
    if (error == ENOENT || error == ENOTDIR) {
        throw MissingFileError(message);
    }
    throw IoError(message);
}

// Closes the descriptor on every path out of the constructor; the mapping outlives it.
class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    ~FileDescriptor() {
        if (fd_ >= 0) {
            ::close(fd_);
        }
    }
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    [[nodiscard]] int get() const { return fd_; }

private:
    int fd_;
};

} // namespace

MappedFile::MappedFile(const std::string& path, Access access) : path_(path) {
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer, forever; the
    // fstat below then refuses it. Regular files ignore the flag.
    const FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
    if (fd.get() < 0) {
        throw_system_error(path, "open", errno);
    }
    struct stat info {};
    if (::fstat(fd.get(), &info) != 0) {
        throw_system_error(path, "stat", errno);
    }
    if (!S_ISREG(info.st_mode)) {
        throw MissingFileError(path + ": cannot open (not a regular file)");
    }
    size_ = static_cast<std::size_t>(info.st_size);
    if (size_ == 0) {
        return; // mmap refuses zero lengths; an empty view is all there is
    }
    void* mapping = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd.get(), 0);
    if (mapping == MAP_FAILED) {
        const int error = errno;
        size_ = 0;
        throw_system_error(path, "map", error);
    }
    // Parsers read front to back within each chunk: ask the kernel to read ahead. A reader in
    // parts would pay for reading what it never touches.
    ::madvise(mapping, size_, access == Access::whole ? MADV_WILLNEED : MADV_RANDOM);
    data_ = static_cast<const char*>(mapping);
}

MappedFile::MappedFile(std::string name, std::string_view bytes)
    : path_(std::move(name)), data_(bytes.data()), size_(bytes.size()), owned_(false) {}

MappedFile::~MappedFile() {
    unmap();
}

MappedFile::MappedFile(MappedFile&& other) noexcept
    : path_(std::move(other.path_)), data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)), owned_(other.owned_) {}

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
    if (this != &other) {
        unmap();
        path_ = std::move(other.path_);
        data_ = std::exchange(other.data_, nullptr);
        size_ = std::exchange(other.size_, 0);
        owned_ = other.owned_;
    }
    return *this;
}

void MappedFile::unmap() noexcept {
    if (data_ != nullptr && owned_) {
        ::munmap(const_cast<char*>(data_), size_);
    }
    data_ = nullptr;
    size_ = 0;
}

std::optional<std::size_t> MappedFile::resident_bytes() const {
    if (!owned_ || data_ == nullptr) {
        return std::nullopt;
    }
    // smaps lists each mapping as "start-end perms ..." and then its fields, "Rss:" among them.
    std::ifstream smaps("/proc/self/smaps");
    if (!smaps) {
        return std::nullopt;
    }
    const auto start = reinterpret_cast<std::uintptr_t>(data_);
    std::string line;
    bool ours = false;
    while (std::getline(smaps, line)) {
        unsigned long long first = 0;
        unsigned long long last = 0;
        char dash = 0;
        if (std::sscanf(line.c_str(), "%llx%c%llx", &first, &dash, &last) == 3 && dash == '-') {
            ours = first == start;
            continue;
        }
        unsigned long long kib = 0;
        if (ours && std::sscanf(line.c_str(), "Rss: %llu kB", &kib) == 1) {
            return static_cast<std::size_t>(kib) * 1024;
        }
    }
    return std::nullopt;
}

} // namespace lfprobe
