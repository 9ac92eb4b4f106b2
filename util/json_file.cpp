#include "util/json_file.h"

#include <filesystem>
#include <fstream>

#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

nlohmann::json read_json(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw_file_error(path, "not found");
    // A FIFO would block forever, a directory reads as nothing.
    if (!fs::is_regular_file(path, ec)) throw_file_error(path, "not a regular file (a directory, a FIFO or a device?)");
    try {
        std::ifstream f(path);
        return nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(path, std::string("not valid JSON: ") + e.what());
    }
}

}  // namespace dynsky
