// Decoding EXT_meshopt_compression buffer views with the meshoptimizer library (gltfpack's
// output): vertex attributes (mode ATTRIBUTES, with the OCTAHEDRAL, QUATERNION and EXPONENTIAL
// filters), triangle indices (TRIANGLES) and index sequences (INDICES).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace dynsky {

// Decodes `size` compressed bytes into count x stride bytes; "" or why not.
std::string decode_meshopt_buffer(const std::string& mode, const std::string& filter, size_t count, size_t stride,
                                  const unsigned char* bytes, size_t size, std::vector<unsigned char>* out);

}  // namespace dynsky
