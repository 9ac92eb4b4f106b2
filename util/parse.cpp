#include "util/parse.h"

#include <cctype>

#include <algorithm>
#include <cstdio>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "util/error.h"

namespace dynsky {

std::string number_text(double v, int significant) {
    char text[40];
    std::snprintf(text, sizeof text, "%.*g", significant, v);
    return text;
}

long long parse_whole_number(const std::string& text, const std::string& what, long long min, long long max) {
    auto refuse = [&]() -> long long {
        throw Error(what + ": '" + text + "' is not a whole number in " + std::to_string(min) + ".." +
                    std::to_string(max));
    };
    if (text.empty() || text.size() > 18 || text.find_first_not_of("0123456789") != std::string::npos) refuse();
    long long v = std::stoll(text);
    if (v < min || v > max) refuse();
    return v;
}

unsigned long long parse_seed(const std::string& text, const std::string& what) {
    const std::string top = "18446744073709551615";  // 2^64 - 1
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos || text.size() > top.size() ||
        (text.size() == top.size() && text > top))
        throw Error(what + ": '" + text + "' is not a whole number in 0.." + top);
    return std::stoull(text);
}

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

void parse_frame_size(const std::string& text, int* w, int* h, const std::string& option) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex("^([0-9]+)x([0-9]+)$")))
        throw Error(option + " '" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
    auto side = [&](const std::string& digits) {
        if (digits.size() > 5 || std::stoi(digits) < 1 || std::stoi(digits) > 16384)
            throw Error(option + " '" + text + "': each side must be 1..16384");
        return std::stoi(digits);
    };
    *w = side(m[1]), *h = side(m[2]);
}

std::string percent_decoded(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit((unsigned char)uri[i + 1]) &&
            std::isxdigit((unsigned char)uri[i + 2])) {
            out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

}  // namespace dynsky
