// Located input errors: the message leads with where the problem is, as compilers do.
#include "lfprobe/error.hpp"

namespace lfprobe {

InputError input_error_at(const FileLocation& where, const std::string& what) {
    if (where.has_line) {
        return InputError(where.path + ":" + std::to_string(where.line) + ": " + what);
    }
    return InputError(where.path + ": byte offset " + std::to_string(where.byte_offset) + ": " +
                      what);
}

} // namespace lfprobe
