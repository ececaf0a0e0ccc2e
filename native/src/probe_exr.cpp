#include "lfprobe/probe_exr.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfThreading.h>
#include <ImfVecAttribute.h>
#include <libdeflate.h>
#include <openexr.h>
#include <tbb/parallel_for.h>

#include "exr_zip_bytes.hpp"
#include "lfprobe/error.hpp"

namespace lfprobe {

namespace {

constexpr const char* kProbeFormatAttribute = "lfprobe/format";
constexpr const char* kProbeFormatValue = "lfprobe-probe 1";
constexpr const char* kPositionAttribute = "lfprobe/position";
// Optional: written only for maps that know their texels' coverage (ProbeMap::coverage).
constexpr const char* kCoverageChannel = "coverage";

// The channels every probe file holds, with the type written; a file without one of them is not
// a probe. Listed once for the writer and both readers.
struct ProbeChannel {
    const char* name;
    exr_pixel_type_t type;
};
constexpr std::array<ProbeChannel, 8> kProbeChannels{{{"R", EXR_PIXEL_HALF},
                                                      {"G", EXR_PIXEL_HALF},
                                                      {"B", EXR_PIXEL_HALF},
                                                      {"A", EXR_PIXEL_HALF},
                                                      {"Z", EXR_PIXEL_FLOAT},
                                                      {"N.X", EXR_PIXEL_HALF},
                                                      {"N.Y", EXR_PIXEL_HALF},
                                                      {"N.Z", EXR_PIXEL_HALF}}};

// Refuses a file that lacks one of kProbeChannels; `has(name)` says whether it has that one.
template <typename Has>
void require_probe_channels(const std::string& path, Has&& has) {
    for (const ProbeChannel& channel : kProbeChannels) {
        if (!has(channel.name)) {
            throw InputError(path + ": expected channel '" + channel.name +
                             "' of a probe EXR (R G B A Z N.X N.Y N.Z)");
        }
    }
}

void use_all_cores_for_exr() {
    static std::once_flag once;
    std::call_once(once, [] {
        Imf::setGlobalThreadCount(
            static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
    });
}

// Slices over the map's arrays, shared by reading and writing so the layout is stated once.
Imf::FrameBuffer probe_frame_buffer(ProbeMap& map) {
    const std::size_t n = static_cast<std::size_t>(map.resolution);
    Imf::FrameBuffer fb;
    const char* rgba_names[4] = {"R", "G", "B", "A"};
    for (std::size_t c = 0; c < 4; ++c) {
        fb.insert(rgba_names[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.rgba.data() + c),
                                            4 * sizeof(Imath::half), 4 * sizeof(Imath::half) * n));
    }
    fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(map.distance.data()),
                              sizeof(float), sizeof(float) * n));
    const char* normal_names[3] = {"N.X", "N.Y", "N.Z"};
    for (std::size_t c = 0; c < 3; ++c) {
        fb.insert(normal_names[c],
                  Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.normal.data() + c),
                             3 * sizeof(Imath::half), 3 * sizeof(Imath::half) * n));
    }
    if (!map.coverage.empty()) {
        fb.insert(kCoverageChannel,
                  Imf::Slice(Imf::HALF, reinterpret_cast<char*>(map.coverage.data()),
                             sizeof(Imath::half), sizeof(Imath::half) * n));
    }
    return fb;
}

} // namespace

namespace {

// What a texel can mean (docs/DESIGN.md §3): a distance is NaN (unknown), +inf (empty) or a
// finite number of metres, 0 or more; a confidence lies in [0, 1]; a surface has a radiance and
// a normal that are numbers. Anything else (a negative or -inf distance, a NaN confidence) was
// not written by a bake, and a trace would answer from it without complaint.
void require_meaningful_texels(const ProbeMap& map, const std::string& path) {
    // A pass over the bits first (a half's value as a float is arithmetic here, Imath's table
    // being off): every texel of a file a bake wrote passes it; the message comes from the
    // values, for the first texel that does not.
    const auto unit_half = [](Imath::half h) { // in [0, 1], -0 included; NaN is not
        const std::uint16_t bits = h.bits();
        return bits <= 0x3C00 || bits == 0x8000;
    };
    const auto nan_half = [](Imath::half h) { return (h.bits() & 0x7FFF) > 0x7C00; };
    std::size_t first_bad = map.texel_count();
    for (std::size_t i = 0; i < map.texel_count(); ++i) {
        const float d = map.distance[i];
        bool bad = d < 0.0f || !unit_half(map.rgba[4 * i + 3]) ||
                   (!map.coverage.empty() && !unit_half(map.coverage[i]));
        if (std::isfinite(d)) {
            for (std::size_t c = 0; c < 3; ++c) {
                bad = bad || nan_half(map.rgba[4 * i + c]) || nan_half(map.normal[3 * i + c]);
            }
        }
        if (bad) {
            first_bad = i;
            break;
        }
    }
    if (first_bad == map.texel_count()) {
        return;
    }
    const auto where = [&](std::size_t i) {
        return path + ": texel (" + std::to_string(i % static_cast<std::size_t>(map.resolution)) +
               ", " + std::to_string(i / static_cast<std::size_t>(map.resolution)) + ")";
    };
    for (std::size_t i = first_bad; i < map.texel_count(); ++i) {
        const float d = map.distance[i];
        if (d < 0.0f) {
            throw InputError(where(i) + ": distance " + std::to_string(d) +
                             " (expected 0 or more metres, NaN for unknown, +inf for empty)");
        }
        if (!map.coverage.empty()) {
            const float coverage = static_cast<float>(map.coverage[i]);
            if (!(coverage >= 0.0f && coverage <= 1.0f)) {
                throw InputError(where(i) + ": coverage " + std::to_string(coverage) +
                                 " (expected a number from 0 to 1)");
            }
        }
        const float confidence = static_cast<float>(map.rgba[4 * i + 3]);
        if (!(confidence >= 0.0f && confidence <= 1.0f)) {
            throw InputError(where(i) + ": confidence (A) " + std::to_string(confidence) +
                             " (expected a number from 0 to 1)");
        }
        if (std::isfinite(d)) {
            const glm::vec3 rgb = map.radiance_at(i);
            const glm::vec3 n = map.normal_at(i);
            if (std::isnan(rgb.x) || std::isnan(rgb.y) || std::isnan(rgb.z) || std::isnan(n.x) ||
                std::isnan(n.y) || std::isnan(n.z)) {
                throw InputError(where(i) + ": a surface texel whose radiance or normal is NaN");
            }
        }
    }
}

// Reading with OpenEXR's core (C) API: each block of scanlines is decompressed straight into the
// map's arrays, the blocks on all cores, where the C++ API's per-sample copy took a quarter of
// each read (a 512² probe of the pump-room set on one core: 19.3 -> 14.3 ms; 8.9 ms with ZIP
// blocks inflated by libdeflate, inflate_zip_block). Files this reader
// does not take (tiled, or deep) are read with the C++ API, as before.
thread_local std::string exr_core_message; // the last error the core reported on this thread

void note_exr_core_error(exr_const_context_t, exr_result_t, const char* message) {
    exr_core_message = message != nullptr ? message : "";
}

// What the core said of a failure on this thread: its message, else the code's; forgotten once
// read, so that a later failure is not told with an earlier one's words.
std::string exr_core_failure(exr_result_t result) {
    std::string detail =
        exr_core_message.empty() ? exr_get_default_error_message(result) : exr_core_message;
    exr_core_message.clear();
    return detail;
}

void check_exr_core(exr_result_t result, const std::string& path, const char* doing) {
    if (result != EXR_ERR_SUCCESS) {
        throw InputError(path + ": not a readable probe EXR (" + doing + ": " +
                         exr_core_failure(result) + ")");
    }
}

// A ZIP block of an EXR file (OpenEXR's file layout): zlib-compressed bytes that, inflated, are
// the differences of consecutive bytes (each stored + 128), and then the block's first half of
// bytes interleaved with its second. Inflated with libdeflate, about 2.5 times as fast as the
// zlib the core calls (a 512² pump-room probe: 14.4 -> 8.9 ms on one core); the rest sixteen
// bytes at a time (exr_zip_bytes.hpp). The pipeline's buffers are the core's: the packed bytes in,
// the unpacked out.
exr_result_t inflate_zip_block(exr_decode_pipeline_t* block) {
    const std::size_t packed = block->chunk.packed_size;
    const std::size_t unpacked = block->chunk.unpacked_size;
    auto* out = static_cast<std::uint8_t*>(block->unpacked_buffer);
    if (packed == 0) {
        return EXR_ERR_SUCCESS;
    }
    if (block->packed_buffer == nullptr || out == nullptr) {
        return EXR_ERR_INVALID_ARGUMENT;
    }
    if (packed == unpacked) { // stored as is: the compressed form was no smaller
        if (out != block->packed_buffer) {
            std::memcpy(out, block->packed_buffer, unpacked);
        }
        return EXR_ERR_SUCCESS;
    }
    struct Free {
        void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
    };
    thread_local const std::unique_ptr<libdeflate_decompressor, Free> inflater(
        libdeflate_alloc_decompressor());
    thread_local std::vector<std::uint8_t> bytes;
    if (inflater == nullptr) {
        return EXR_ERR_OUT_OF_MEMORY;
    }
    bytes.resize(unpacked);
    std::size_t inflated = 0;
    if (libdeflate_zlib_decompress(inflater.get(), block->packed_buffer, packed, bytes.data(),
                                   unpacked, &inflated) != LIBDEFLATE_SUCCESS ||
        inflated != unpacked) {
        return EXR_ERR_CORRUPT_CHUNK;
    }
    unpack_zip_bytes(bytes.data(), unpacked, out);
    return EXR_ERR_SUCCESS;
}

class ExrCoreFile {
public:
    explicit ExrCoreFile(const std::string& path) {
        exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
        init.error_handler_fn = note_exr_core_error; // not printed: the exception says it
        exr_core_message.clear();
        check_exr_core(exr_start_read(&context_, path.c_str(), &init), path, "opening");
    }
    ~ExrCoreFile() { exr_finish(&context_); }
    ExrCoreFile(const ExrCoreFile&) = delete;
    ExrCoreFile& operator=(const ExrCoreFile&) = delete;
    [[nodiscard]] exr_context_t context() const { return context_; }

private:
    exr_context_t context_ = nullptr;
};

// Where each of a probe file's channels goes in `map`: its array, and how many values a texel
// holds there; none for a channel the map does not keep.
struct ChannelTarget {
    std::uint8_t* first = nullptr;
    int values_per_texel = 0;
    int bytes_per_value = 0;
    exr_pixel_type_t type = EXR_PIXEL_HALF;
};

ChannelTarget channel_target(ProbeMap& map, const char* name) {
    const auto half_at = [](std::vector<Imath::half>& v, std::size_t offset, int per_texel) {
        return ChannelTarget{reinterpret_cast<std::uint8_t*>(v.data() + offset), per_texel,
                             static_cast<int>(sizeof(Imath::half)), EXR_PIXEL_HALF};
    };
    static constexpr const char* rgba_names[4] = {"R", "G", "B", "A"};
    for (std::size_t c = 0; c < 4; ++c) {
        if (std::strcmp(name, rgba_names[c]) == 0) {
            return half_at(map.rgba, c, 4);
        }
    }
    static constexpr const char* normal_names[3] = {"N.X", "N.Y", "N.Z"};
    for (std::size_t c = 0; c < 3; ++c) {
        if (std::strcmp(name, normal_names[c]) == 0) {
            return half_at(map.normal, c, 3);
        }
    }
    if (std::strcmp(name, "Z") == 0) {
        return ChannelTarget{reinterpret_cast<std::uint8_t*>(map.distance.data()), 1,
                             static_cast<int>(sizeof(float)), EXR_PIXEL_FLOAT};
    }
    if (std::strcmp(name, kCoverageChannel) == 0 && !map.coverage.empty()) {
        return half_at(map.coverage, 0, 1);
    }
    return {};
}

// The probe in `path` read with the core API; none where the file is not one of scanlines
// (then the C++ API reads it).
std::optional<ProbeMap> read_probe_exr_core(const std::string& path) {
    const ExrCoreFile file(path);
    const exr_context_t ctxt = file.context();
    exr_storage_t storage{};
    check_exr_core(exr_get_storage(ctxt, 0, &storage), path, "its storage");
    if (storage != EXR_STORAGE_SCANLINE) {
        return std::nullopt;
    }
    exr_attr_box2i_t window{};
    check_exr_core(exr_get_data_window(ctxt, 0, &window), path, "its data window");
    const std::int64_t w = std::int64_t{window.max.x} - window.min.x + 1;
    const std::int64_t h = std::int64_t{window.max.y} - window.min.y + 1;
    if (w != h || w < 1 || window.min.x != 0 || window.min.y != 0) {
        throw InputError(path +
                         ": expected a square probe map with its data window at (0, 0), got " +
                         std::to_string(w) + "×" + std::to_string(h));
    }
    if (w > kMaxProbeResolution) {
        throw InputError(path + ": a probe map of " + std::to_string(w) + "² texels (at most " +
                         std::to_string(kMaxProbeResolution) + "² are read)");
    }
    const exr_attr_chlist_t* channels = nullptr;
    check_exr_core(exr_get_channels(ctxt, 0, &channels), path, "its channels");
    const auto has_channel = [&](const char* name) {
        for (int c = 0; c < channels->num_channels; ++c) {
            if (std::strcmp(channels->entries[c].name.str, name) == 0) {
                return true;
            }
        }
        return false;
    };
    require_probe_channels(path, has_channel);
    exr_attr_v3d_t stored{};
    glm::dvec3 position(0.0);
    if (exr_attr_get_v3d(ctxt, 0, kPositionAttribute, &stored) == EXR_ERR_SUCCESS) {
        position = glm::dvec3(stored.x, stored.y, stored.z);
    }
    exr_core_message.clear(); // a missing position is no error
    const int n = static_cast<int>(w);
    ProbeMap map(n, position);
    if (has_channel(kCoverageChannel)) {
        map.coverage.assign(map.texel_count(), Imath::half(1.0f));
    }
    int lines = 0;
    check_exr_core(exr_get_scanlines_per_chunk(ctxt, 0, &lines), path, "its blocks");
    if (lines < 1) {
        throw InputError(path + ": not a readable probe EXR (" + std::to_string(lines) +
                         " scanlines a block)");
    }
    exr_compression_t compression{};
    check_exr_core(exr_get_compression(ctxt, 0, &compression), path, "its compression");
    const bool zip = compression == EXR_COMPRESSION_ZIP || compression == EXR_COMPRESSION_ZIPS;
    const int blocks = (n + lines - 1) / lines;
    tbb::parallel_for(0, blocks, [&](int block) {
        exr_chunk_info_t chunk{};
        check_exr_core(exr_read_scanline_chunk_info(ctxt, 0, block * lines, &chunk), path,
                       "a block's place");
        exr_decode_pipeline_t decoder{}; // all zero, as EXR_DECODE_PIPELINE_INITIALIZER
        check_exr_core(exr_decoding_initialize(ctxt, 0, &chunk, &decoder), path,
                       "a block's layout");
        struct Release {
            exr_const_context_t context;
            exr_decode_pipeline_t* pipeline;
            ~Release() { exr_decoding_destroy(context, pipeline); }
        } release{ctxt, &decoder};
        const std::size_t first_texel = static_cast<std::size_t>(chunk.start_y) * n;
        for (int c = 0; c < decoder.channel_count; ++c) {
            exr_coding_channel_info_t& channel = decoder.channels[c];
            const ChannelTarget target = channel_target(map, channel.channel_name);
            if (target.first == nullptr) {
                channel.decode_to_ptr = nullptr; // a channel the map does not keep: skipped
                continue;
            }
            const int texel_bytes = target.values_per_texel * target.bytes_per_value;
            channel.decode_to_ptr = target.first + first_texel * texel_bytes;
            channel.user_pixel_stride = texel_bytes;
            channel.user_line_stride = texel_bytes * n;
            channel.user_bytes_per_element = static_cast<std::int16_t>(target.bytes_per_value);
            channel.user_data_type = static_cast<std::uint16_t>(target.type);
        }
        check_exr_core(exr_decoding_choose_default_routines(ctxt, 0, &decoder), path,
                       "a block's decoder");
        if (zip && decoder.decompress_fn != nullptr) {
            decoder.decompress_fn = inflate_zip_block;
        }
        check_exr_core(exr_decoding_run(ctxt, 0, &decoder), path, "a block's pixels");
    });
    return map;
}

// Writing: the blocks of 16 scanlines packed as the format lays them out (a row of each channel
// in turn, in the header's order, little-endian) and compressed on all cores, ZIP-encoded with
// libdeflate at level 1, then written in order through the core API. Level 1 against 4 and 6:
// a 2048² probe's file within 1 % of the same size, written in 265 against 309 and 356 ms. Each
// block is the inverse of inflate_zip_block: the bytes split into the even and the odd ones, each
// byte stored as its difference from the one before + 128, the whole deflated (zlib format); a
// block that would not shrink is stored as it is, as readers expect.
static_assert(std::endian::native == std::endian::little,
              "probe files are little-endian: a big-endian host would swap bytes when packing");

constexpr int kZipLinesPerBlock = 16;
constexpr int kZipLevel = 1;

std::vector<std::uint8_t> zip_block(std::vector<std::uint8_t>& raw) {
    const std::size_t size = raw.size();
    std::vector<std::uint8_t> shuffled(size);
    pack_zip_bytes(raw.data(), size, shuffled.data());
    struct Free {
        void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
    };
    thread_local const std::unique_ptr<libdeflate_compressor, Free> deflater(
        libdeflate_alloc_compressor(kZipLevel));
    if (deflater == nullptr) {
        throw std::bad_alloc();
    }
    std::vector<std::uint8_t> packed(libdeflate_zlib_compress_bound(deflater.get(), size));
    const std::size_t written = libdeflate_zlib_compress(deflater.get(), shuffled.data(), size,
                                                         packed.data(), packed.size());
    if (written == 0 || written >= size) {
        return std::move(raw); // stored as is
    }
    packed.resize(written);
    return packed;
}

// Writes `map` to the file `tmp`; errors name `path`, the file the caller renames it to.
void write_probe_exr_core(const std::string& tmp, const std::string& path, const ProbeMap& map) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = note_exr_core_error;
    exr_core_message.clear();
    exr_context_t ctxt = nullptr;
    const auto check = [&](exr_result_t result, const char* doing) {
        if (result != EXR_ERR_SUCCESS) {
            throw IoError(path + ": cannot write probe EXR (" + doing + ": " +
                          exr_core_failure(result) + ")");
        }
    };
    check(exr_start_write(&ctxt, tmp.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), "opening");
    struct Finish {
        exr_context_t* context;
        ~Finish() { exr_finish(context); }
    } finish{&ctxt};
    const int n = map.resolution;
    int part = 0;
    check(exr_add_part(ctxt, nullptr, EXR_STORAGE_SCANLINE, &part), "its part");
    check(exr_initialize_required_attr_simple(ctxt, part, n, n, EXR_COMPRESSION_ZIP), "its header");
    for (const ProbeChannel& channel : kProbeChannels) {
        check(exr_add_channel(ctxt, part, channel.name, channel.type, EXR_PERCEPTUALLY_LOGARITHMIC,
                              1, 1),
              "a channel");
    }
    if (!map.coverage.empty()) {
        check(exr_add_channel(ctxt, part, kCoverageChannel, EXR_PIXEL_HALF,
                              EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
              "a channel");
    }
    check(exr_attr_set_string(ctxt, part, kProbeFormatAttribute, kProbeFormatValue), "its format");
    const exr_attr_v3d_t position{{{map.position.x, map.position.y, map.position.z}}};
    check(exr_attr_set_v3d(ctxt, part, kPositionAttribute, &position), "its position");
    check(exr_write_header(ctxt), "its header");
    // The channels in the order the header lists them (sorted by name), where the map keeps
    // each (the reader's table: the map is only read here).
    const exr_attr_chlist_t* listed = nullptr;
    check(exr_get_channels(ctxt, part, &listed), "its channels");
    std::vector<ChannelTarget> order;
    std::size_t row_bytes = 0;
    for (int c = 0; c < listed->num_channels; ++c) {
        order.push_back(channel_target(const_cast<ProbeMap&>(map), listed->entries[c].name.str));
        row_bytes += static_cast<std::size_t>(order.back().bytes_per_value) * n;
    }
    const int blocks = (n + kZipLinesPerBlock - 1) / kZipLinesPerBlock;
    std::vector<std::vector<std::uint8_t>> packed(static_cast<std::size_t>(blocks));
    tbb::parallel_for(0, blocks, [&](int block) {
        const int y0 = block * kZipLinesPerBlock;
        const int y1 = std::min(n, y0 + kZipLinesPerBlock);
        std::vector<std::uint8_t> raw(row_bytes * static_cast<std::size_t>(y1 - y0));
        std::uint8_t* to = raw.data();
        for (int y = y0; y < y1; ++y) {
            for (const ChannelTarget& channel : order) {
                const std::size_t texel_bytes =
                    static_cast<std::size_t>(channel.values_per_texel) * channel.bytes_per_value;
                const std::uint8_t* from =
                    channel.first + static_cast<std::size_t>(y) * n * texel_bytes;
                for (int x = 0; x < n; ++x) {
                    std::memcpy(to, from, static_cast<std::size_t>(channel.bytes_per_value));
                    to += channel.bytes_per_value;
                    from += texel_bytes;
                }
            }
        }
        packed[static_cast<std::size_t>(block)] = zip_block(raw);
    });
    for (int block = 0; block < blocks; ++block) {
        const std::vector<std::uint8_t>& bytes = packed[static_cast<std::size_t>(block)];
        check(exr_write_scanline_chunk(ctxt, part, block * kZipLinesPerBlock, bytes.data(),
                                       bytes.size()),
              "a block");
    }
}

} // namespace

void write_probe_exr(const std::string& path, const ProbeMap& map) {
    const std::string tmp = temporary_path_for(path);
    try {
        write_probe_exr_core(tmp, path, map);
        std::filesystem::rename(tmp, path);
    } catch (const std::exception& e) {
        std::error_code ignored;
        std::filesystem::remove(tmp, ignored);
        if (dynamic_cast<const IoError*>(&e) != nullptr) {
            throw;
        }
        throw IoError(path + ": cannot write probe EXR (" + e.what() + ")");
    }
}

ProbeMap read_probe_exr(const std::string& path) {
    use_all_cores_for_exr();
    if (!std::filesystem::exists(path)) {
        throw MissingFileError(path + ": no such probe file");
    }
    if (std::optional<ProbeMap> map = read_probe_exr_core(path)) {
        require_meaningful_texels(*map, path);
        return std::move(*map);
    }
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i window = file.header().dataWindow();
        const int w = window.max.x - window.min.x + 1;
        const int h = window.max.y - window.min.y + 1;
        if (w != h || w < 1 || window.min.x != 0 || window.min.y != 0) {
            throw InputError(path +
                             ": expected a square probe map with its data window at (0, 0), "
                             "got " +
                             std::to_string(w) + "×" + std::to_string(h));
        }
        const Imf::ChannelList& channels = file.header().channels();
        require_probe_channels(
            path, [&](const char* name) { return channels.findChannel(name) != nullptr; });
        glm::dvec3 position(0.0);
        if (const auto* attr =
                file.header().findTypedAttribute<Imf::V3dAttribute>(kPositionAttribute)) {
            position = glm::dvec3(attr->value().x, attr->value().y, attr->value().z);
        }
        ProbeMap map(w, position);
        if (channels.findChannel(kCoverageChannel) != nullptr) {
            map.coverage.assign(map.texel_count(), Imath::half(1.0f));
        }
        file.setFrameBuffer(probe_frame_buffer(map));
        file.readPixels(window.min.y, window.max.y);
        require_meaningful_texels(map, path);
        return map;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path + ": not a readable probe EXR (" + e.what() + ")");
    }
}

} // namespace lfprobe
