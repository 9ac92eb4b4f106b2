#include "util/npy.h"

#include <cstring>
#include <fstream>
#include <sstream>

#include "util/atomic_file.h"
#include "util/error.h"

namespace dynsky {

NpyArray read_npy(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw_file_error(path, "cannot open the file");
    char magic[8];
    f.read(magic, 8);
    if (!f || std::memcmp(magic, "\x93NUMPY", 6) != 0) throw_file_error(path, "not a .npy file");
    uint32_t header_len = 0;
    if (magic[6] == 1) {
        unsigned char b[2];
        f.read(reinterpret_cast<char*>(b), 2);
        header_len = b[0] | (b[1] << 8);
    } else {
        unsigned char b[4];
        f.read(reinterpret_cast<char*>(b), 4);
        header_len = b[0] | (b[1] << 8) | (b[2] << 16) | (uint32_t(b[3]) << 24);
    }
    std::string header(header_len, '\0');
    f.read(header.data(), header_len);
    if (!f) throw_file_error(path, "truncated .npy header");
    auto field = [&](const std::string& key) {
        size_t p = header.find("'" + key + "'");
        if (p == std::string::npos) throw_file_error(path, ".npy header lacks '" + key + "'");
        return header.substr(header.find(':', p) + 1);
    };
    std::string descr = field("descr");
    bool is_f4 = descr.find("<f4") != std::string::npos,
         is_u1 = descr.find("|u1") != std::string::npos || descr.find("|b1") != std::string::npos;
    if (!is_f4 && !is_u1) throw_file_error(path, "only float32 and uint8 .npy files are supported");
    std::string order = field("fortran_order");
    if (order.substr(0, order.find(',')).find("True") != std::string::npos)
        throw_file_error(path, "Fortran-order .npy is not supported");
    std::string s = field("shape");
    s = s.substr(s.find('(') + 1, s.find(')') - s.find('(') - 1);
    NpyArray a;
    std::stringstream ss(s);
    std::string item;
    size_t count = 1;
    while (std::getline(ss, item, ',')) {
        if (item.find_first_not_of(" ") == std::string::npos) continue;
        a.shape.push_back(std::stoull(item));
        count *= a.shape.back();
    }
    a.data.resize(count);
    if (is_f4) {
        f.read(reinterpret_cast<char*>(a.data.data()), std::streamsize(count * 4));
    } else {
        std::vector<unsigned char> b(count);
        f.read(reinterpret_cast<char*>(b.data()), std::streamsize(count));
        for (size_t i = 0; i < count; ++i) a.data[i] = b[i];
    }
    if (!f) throw_file_error(path, "truncated .npy data");
    return a;
}

namespace {
void write_npy_raw(const std::string& path, const std::vector<size_t>& shape, const char* descr, const void* data,
                   size_t bytes_count) {
    std::string dict = std::string("{'descr': '") + descr + "', 'fortran_order': False, 'shape': (";
    for (size_t i = 0; i < shape.size(); ++i)
        dict += std::to_string(shape[i]) + (shape.size() == 1 || i + 1 < shape.size() ? "," : "");
    dict += "), }";
    size_t total = 10 + dict.size() + 1;
    dict += std::string((64 - total % 64) % 64, ' ') + "\n";
    std::string bytes("\x93NUMPY\x01\x00", 8);
    bytes += char(dict.size() & 0xff), bytes += char(dict.size() >> 8);
    bytes += dict;
    bytes.append(static_cast<const char*>(data), bytes_count);
    write_file_atomic(path, bytes);
}
size_t element_count(const std::vector<size_t>& shape) {
    size_t n = 1;
    for (size_t s : shape) n *= s;
    return n;
}
}  // namespace

void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data) {
    write_npy_raw(path, shape, "<f4", data, element_count(shape) * 4);
}
void write_npy(const std::string& path, const std::vector<size_t>& shape, const unsigned char* data) {
    write_npy_raw(path, shape, "|u1", data, element_count(shape));
}

}  // namespace dynsky
