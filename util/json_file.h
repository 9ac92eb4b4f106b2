// Reading JSON files (nlohmann::json) with errors that name the file.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace dynsky {

nlohmann::json read_json(const std::string& path);  // throws dynsky::Error: not found, not JSON

}  // namespace dynsky
