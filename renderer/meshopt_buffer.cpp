#include "renderer/meshopt_buffer.h"

#include <meshoptimizer.h>

namespace dynsky {

std::string decode_meshopt_buffer(const std::string& mode, const std::string& filter, size_t count, size_t stride,
                                  const unsigned char* bytes, size_t size, std::vector<unsigned char>* out) {
    if (count == 0 || stride == 0) return "count and byteStride must be positive";
    if (count > (size_t(1) << 31) / stride) return "count x byteStride is beyond 2 GiB";
    // meshoptimizer's codecs shrink data a few times, constant data some tens of times; a count
    // claiming more than this of so few bytes is a corrupt file, not a mesh to allocate for.
    if (count * stride > 256 * size + (size_t(1) << 20))
        return "count x byteStride (" + std::to_string(count * stride) + " bytes) is beyond what " +
               std::to_string(size) + " compressed bytes can hold";
    out->assign(count * stride, 0);
    int rc = 0;
    if (mode == "ATTRIBUTES") {
        if (stride % 4 != 0 || stride > 256) return "an ATTRIBUTES byteStride must be a multiple of 4, at most 256";
        rc = meshopt_decodeVertexBuffer(out->data(), count, stride, bytes, size);
        if (rc == 0) {
            if (filter == "OCTAHEDRAL") {
                if (stride != 4 && stride != 8) return "the OCTAHEDRAL filter needs byteStride 4 or 8";
                meshopt_decodeFilterOct(out->data(), count, stride);
            } else if (filter == "QUATERNION") {
                if (stride != 8) return "the QUATERNION filter needs byteStride 8";
                meshopt_decodeFilterQuat(out->data(), count, stride);
            } else if (filter == "EXPONENTIAL") {
                meshopt_decodeFilterExp(out->data(), count, stride);
            } else if (filter != "NONE") {
                return "unknown filter '" + filter + "'";
            }
        }
    } else if (mode == "TRIANGLES" || mode == "INDICES") {
        if (stride != 2 && stride != 4) return "an index byteStride must be 2 or 4";
        if (filter != "NONE") return "indices take no filter";
        if (mode == "TRIANGLES" && count % 3 != 0) return "a TRIANGLES count must be a multiple of 3";
        rc = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out->data(), count, stride, bytes, size)
                                 : meshopt_decodeIndexSequence(out->data(), count, stride, bytes, size);
    } else {
        return "unknown mode '" + mode + "'";
    }
    if (rc != 0) return "the compressed data does not decode (meshoptimizer error " + std::to_string(rc) + ")";
    return "";
}

}  // namespace dynsky
