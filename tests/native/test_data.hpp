// Where the tests find the project's shared test data (../shared/data beside the checkout):
// the environment variable LFPROBE_SHARED_DATA, which tools/test.sh sets, else the folder the
// build was configured with.
#pragma once

#include <cstdlib>
#include <string>

namespace lfprobe::testing {

[[nodiscard]] inline std::string shared_data(const std::string& relative) {
    const char* from_environment = std::getenv("LFPROBE_SHARED_DATA");
    const std::string root = from_environment != nullptr ? from_environment : LFPROBE_SHARED_DATA;
    return root + "/" + relative;
}

} // namespace lfprobe::testing
