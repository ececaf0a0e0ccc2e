// A read-only memory mapping of a whole file, so that parsers can hand byte ranges of it to
// worker threads without copying.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace lfprobe {

class MappedFile {
public:
    // How the file will be read: whole (the kernel reads it ahead), or in parts that the
    // reader picks (only the pages touched are read: a spatial cloud's cut).
    enum class Access { whole, in_parts };

    // Maps `path` read-only. An empty file maps to an empty view. Throws IoError naming the
    // path and the system's reason when the file cannot be opened or mapped.
    explicit MappedFile(const std::string& path, Access access = Access::whole);
    // A view of `bytes` already in memory, which the caller keeps alive, named `name` in errors:
    // the readers parse a buffer exactly as a file (the fuzz harnesses, data from memory).
    MappedFile(std::string name, std::string_view bytes);
    ~MappedFile();

    MappedFile(const MappedFile&) = delete;
    MappedFile& operator=(const MappedFile&) = delete;
    MappedFile(MappedFile&& other) noexcept;
    MappedFile& operator=(MappedFile&& other) noexcept;

    [[nodiscard]] const char* data() const { return data_; }
    [[nodiscard]] std::size_t size() const { return size_; }
    [[nodiscard]] std::string_view view() const { return {data_, size_}; }
    [[nodiscard]] const std::string& path() const { return path_; }
    // The bytes of the mapping this process has touched and holds in memory (its resident
    // pages, /proc/self/smaps); none where the system does not say, or for a borrowed view.
    [[nodiscard]] std::optional<std::size_t> resident_bytes() const;

private:
    void unmap() noexcept;

    std::string path_;
    const char* data_ = nullptr;
    std::size_t size_ = 0;
    bool owned_ = true; // a mapping to unmap, not a borrowed view
};

} // namespace lfprobe
