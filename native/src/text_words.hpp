// Splitting a line of a text format (PLY headers, OBJ, MTL) into words.
#pragma once

#include <string_view>
#include <vector>

namespace lfprobe {

// The words of `line`, separated by runs of spaces, tabs and carriage returns.
[[nodiscard]] inline std::vector<std::string_view> split_words(std::string_view line) {
    std::vector<std::string_view> words;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) {
            ++i;
        }
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') {
            ++i;
        }
        if (i > start) {
            words.push_back(line.substr(start, i - start));
        }
    }
    return words;
}

} // namespace lfprobe
