#include "util/json_file.h"

#include <filesystem>
#include <fstream>

#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

nlohmann::json read_json(const std::string& path) {
    if (!fs::exists(path)) throw_file_error(path, "not found");
    try {
        std::ifstream f(path);
        return nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
        throw_file_error(path, std::string("not valid JSON: ") + e.what());
    }
}

}  // namespace dynsky
