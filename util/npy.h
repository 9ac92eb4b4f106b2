// .npy files (NumPy's format): how the Python side (networks/) and the C++ side exchange data
// sets and reference input/output pairs.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// Little-endian float32 or uint8, C order.
struct NpyArray {
    std::vector<size_t> shape;
    std::vector<float> data;  // uint8 files are converted to float
};
NpyArray read_npy(const std::string& path);  // throws dynsky::Error naming the file
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data);
void write_npy(const std::string& path, const std::vector<size_t>& shape, const unsigned char* data);

}  // namespace dynsky
