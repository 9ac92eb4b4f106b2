#include "util/parse.h"

#include <algorithm>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "util/error.h"

namespace dynsky {

std::vector<int> parse_int_list(const std::string& text, const std::string& option) {
    std::vector<int> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        try {
            size_t used = 0;
            int v = std::stoi(item, &used);
            if (used != item.size() || v < 1) throw std::invalid_argument("");
            out.push_back(v);
        } catch (const std::exception&) {
            throw Error(option + ": '" + item + "' is not a positive whole number (write e.g. 1,2,3,6)");
        }
    }
    if (out.empty()) throw Error(option + ": give at least one value");
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

void parse_frame_size(const std::string& text, int* w, int* h) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)x([0-9]+)$")))
        throw Error("--res '" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
    *w = std::stoi(m[1]), *h = std::stoi(m[2]);
    if (*w < 1 || *h < 1 || *w > 16384 || *h > 16384) throw Error("--res '" + text + "': each side must be 1..16384");
}

}  // namespace dynsky
