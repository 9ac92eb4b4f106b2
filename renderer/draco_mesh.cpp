#include "renderer/draco_mesh.h"

#include <draco/compression/decode.h>

#include "util/error.h"

namespace dynsky {

struct DracoMesh::Impl {
    std::unique_ptr<draco::Mesh> mesh;
};

DracoMesh::DracoMesh(const unsigned char* bytes, size_t size) : impl_(std::make_unique<Impl>()) {
    draco::DecoderBuffer in;
    in.Init(reinterpret_cast<const char*>(bytes), size);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&in);
    if (!decoded.ok()) throw Error(decoded.status().error_msg_string());
    impl_->mesh = std::move(decoded).value();
    if (!impl_->mesh) throw Error("no mesh");
}

DracoMesh::~DracoMesh() = default;

size_t DracoMesh::points() const { return impl_->mesh->num_points(); }

std::vector<uint32_t> DracoMesh::indices() const {
    const draco::Mesh& m = *impl_->mesh;
    std::vector<uint32_t> out;
    out.reserve(3 * size_t(m.num_faces()));
    for (draco::FaceIndex f(0); f < m.num_faces(); ++f)
        for (int k = 0; k < 3; ++k) out.push_back(m.face(f)[k].value());
    return out;
}

int DracoMesh::components(uint32_t unique_id) const {
    const draco::PointAttribute* a = impl_->mesh->GetAttributeByUniqueId(unique_id);
    return a ? int(a->num_components()) : 0;
}

bool DracoMesh::attribute(uint32_t unique_id, int components, std::vector<float>* values) const {
    const draco::PointAttribute* a = impl_->mesh->GetAttributeByUniqueId(unique_id);
    if (!a || components < 1 || components > 4) return false;
    const size_t n = points();
    values->assign(n * size_t(components), 0.0f);
    for (size_t i = 0; i < n; ++i)
        if (!a->ConvertValue<float>(a->mapped_index(draco::PointIndex(uint32_t(i))), int8_t(components),
                                    values->data() + i * size_t(components)))
            return false;
    return true;
}

}  // namespace dynsky
