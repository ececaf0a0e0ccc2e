// The names an enum's values take in files, options and messages: one table per enum, read
// both ways, so a name is spelt in one place. A table may give a value several names (aliases
// a reader accepts); the first row for a value is the name it is written with.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include "lfprobe/error.hpp"

namespace lfprobe {

template <class Enum>
struct EnumName {
    Enum value;
    const char* name; // a string literal: lives as long as the program
};

// The name `value` is written with, or `unnamed` when the table has no row for it.
template <class Enum, std::size_t N>
[[nodiscard]] constexpr const char* name_of(const std::array<EnumName<Enum>, N>& table, Enum value,
                                            const char* unnamed = "?") {
    const auto row = std::find_if(table.begin(), table.end(),
                                  [&](const EnumName<Enum>& r) { return r.value == value; });
    return row == table.end() ? unnamed : row->name;
}

// The value `name` stands for (exact match), or nullopt.
template <class Enum, std::size_t N>
[[nodiscard]] constexpr std::optional<Enum> value_named(const std::array<EnumName<Enum>, N>& table,
                                                        std::string_view name) {
    const auto row = std::find_if(table.begin(), table.end(), [&](const EnumName<Enum>& r) {
        return std::string_view(r.name) == name;
    });
    return row == table.end() ? std::nullopt : std::optional<Enum>(row->value);
}

// The value `name` stands for; InputError(`message`) when the table does not know it.
template <class Enum, std::size_t N>
[[nodiscard]] Enum value_named_or_throw(const std::array<EnumName<Enum>, N>& table,
                                        std::string_view name, const std::string& message) {
    if (const auto value = value_named(table, name)) {
        return *value;
    }
    throw InputError(message);
}

} // namespace lfprobe
