// libFuzzer harness: the OBJ reader with its material library and a texture. The input is the
// OBJ, then after a line "--mtl--" the MTL (written as m.mtl), then after "--tex--" the bytes of
// t.png; the seeds name them (mtllib m.mtl, map_Kd t.png).
#include <cstdint>
#include <string_view>

#include "lfprobe/error.hpp"
#include "lfprobe/mesh_reader.hpp"
#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace lfprobe;
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);
    const auto [obj, rest] = fuzz::split_at(bytes, "\n--mtl--\n");
    const auto [mtl, texture] = fuzz::split_at(rest, "\n--tex--\n");
    fuzz::write_scratch_file("m.mtl", mtl);
    fuzz::write_scratch_file("t.png", texture);
    const std::string path = fuzz::write_scratch_file("m.obj", obj);
    try {
        fuzz::check_mesh(read_obj(path));
    } catch (const InputError&) {
    } catch (const IoError&) {
    }
    return 0;
}
