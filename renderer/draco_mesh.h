// A KHR_draco_mesh_compression buffer decoded by Google's draco library, kept apart from the glTF
// loader (draco's headers and tinygltf's break each other in one translation unit: the loader's
// frees crashed). Attributes come out as floats per vertex, normalised integers mapped to [0, 1] or
// [-1, 1] as draco's ConvertValue does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace dynsky {

class DracoMesh {
  public:
    // Decodes `size` bytes; throws dynsky::Error with draco's own words when they do not decode.
    DracoMesh(const unsigned char* bytes, size_t size);
    ~DracoMesh();
    DracoMesh(const DracoMesh&) = delete;
    DracoMesh& operator=(const DracoMesh&) = delete;

    size_t points() const;                  // vertices
    std::vector<uint32_t> indices() const;  // 3 per triangle
    // Components of the attribute with this unique id (the glTF extension's attribute ids); 0: none.
    int components(uint32_t unique_id) const;
    // Its values, `components` floats per vertex; false when draco cannot convert them.
    bool attribute(uint32_t unique_id, int components, std::vector<float>* values) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace dynsky
