#include "renderer/mesh_attributes.h"

namespace dynsky {
namespace {

template <typename T>
std::vector<T> gather(const std::vector<T>& values, const std::vector<uint32_t>& indices) {
    if (values.empty()) return {};
    std::vector<T> out;
    out.reserve(indices.size());
    for (uint32_t i : indices) out.push_back(values[i]);
    return out;
}

// A unit vector perpendicular to n (any one): the fallback tangent.
Vec3 any_perpendicular(const Vec3& n) {
    Vec3 t, b;
    orthonormal_basis(n, &t, &b);
    return t;
}

}  // namespace

void generate_flat_normals(TriangleMesh& mesh) {
    const std::vector<uint32_t>& idx = mesh.indices;
    mesh.positions = gather(mesh.positions, idx);
    mesh.tangents = gather(mesh.tangents, idx);
    for (auto& uv : mesh.texcoords) uv = gather(uv, idx);
    mesh.colors = gather(mesh.colors, idx);
    mesh.normals.assign(mesh.positions.size(), Vec3::UnitZ());
    for (size_t i = 0; i < idx.size(); ++i) mesh.indices[i] = uint32_t(i);
    for (size_t t = 0; t + 2 < mesh.positions.size(); t += 3) {
        const Vec3 &p0 = mesh.positions[t], &p1 = mesh.positions[t + 1], &p2 = mesh.positions[t + 2];
        Vec3 n = (p1 - p0).cross(p2 - p0);
        float len = n.norm();
        if (len > 0 && std::isfinite(len)) n /= len;
        else n = Vec3::UnitZ();
        mesh.normals[t] = mesh.normals[t + 1] = mesh.normals[t + 2] = n;
    }
}

void generate_smooth_normals(TriangleMesh& mesh) {
    std::vector<Vec3> sum(mesh.positions.size(), Vec3::Zero());
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        uint32_t i0 = mesh.indices[t], i1 = mesh.indices[t + 1], i2 = mesh.indices[t + 2];
        // |cross| is twice the area: summing unnormalised cross products weights by area.
        Vec3 n = (mesh.positions[i1] - mesh.positions[i0]).cross(mesh.positions[i2] - mesh.positions[i0]);
        if (!n.allFinite()) continue;
        sum[i0] += n, sum[i1] += n, sum[i2] += n;
    }
    mesh.normals.resize(sum.size());
    for (size_t i = 0; i < sum.size(); ++i) {
        float len = sum[i].norm();
        mesh.normals[i] = len > 0 ? Vec3(sum[i] / len) : Vec3::UnitZ();
    }
}

void generate_tangents(TriangleMesh& mesh, int texcoord) {
    const size_t n_vertices = mesh.positions.size();
    if (mesh.normals.size() != n_vertices) generate_smooth_normals(mesh);
    const std::vector<Vec2>* uv = nullptr;
    if (texcoord >= 0 && texcoord < 2 && mesh.texcoords[texcoord].size() == n_vertices) uv = &mesh.texcoords[texcoord];
    else if (mesh.texcoords[0].size() == n_vertices) uv = &mesh.texcoords[0];

    std::vector<Vec3> tangent_sum(n_vertices, Vec3::Zero()), up_sum(n_vertices, Vec3::Zero());
    if (uv) {
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
            uint32_t i[3] = {mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
            Vec3 e1 = mesh.positions[i[1]] - mesh.positions[i[0]], e2 = mesh.positions[i[2]] - mesh.positions[i[0]];
            Vec2 d1 = (*uv)[i[1]] - (*uv)[i[0]], d2 = (*uv)[i[2]] - (*uv)[i[0]];
            float det = d1.x() * d2.y() - d2.x() * d1.y();
            float area = 0.5f * e1.cross(e2).norm();
            if (!(std::abs(det) > 1e-20f) || !(area > 0) || !std::isfinite(area)) continue;
            // Solve [e1 e2] = [dPdu dPdv] [d1 d2] for the surface derivatives.
            Vec3 dpdu = (d2.y() * e1 - d1.y() * e2) / det;
            Vec3 dpdv = (d1.x() * e2 - d2.x() * e1) / det;
            float lu = dpdu.norm(), lv = dpdv.norm();
            if (!(lu > 0) || !(lv > 0) || !std::isfinite(lu) || !std::isfinite(lv)) continue;
            // Normalise before weighting: dP/du's length depends on the UV scale, not the shape.
            Vec3 tw = dpdu * (area / lu), uw = -dpdv * (area / lv);
            for (uint32_t k : i) tangent_sum[k] += tw, up_sum[k] += uw;
        }
    }
    mesh.tangents.resize(n_vertices);
    for (size_t k = 0; k < n_vertices; ++k) {
        const Vec3& n = mesh.normals[k];
        Vec3 t = tangent_sum[k] - n * n.dot(tangent_sum[k]);
        float len = t.norm();
        if (len > 1e-12f * std::max(1.0f, tangent_sum[k].norm()) && std::isfinite(len)) {
            t /= len;
            float w = n.cross(t).dot(up_sum[k]) < 0 ? -1.0f : 1.0f;
            mesh.tangents[k] = Vec4(t.x(), t.y(), t.z(), w);
        } else {
            Vec3 a = any_perpendicular(n);
            mesh.tangents[k] = Vec4(a.x(), a.y(), a.z(), 1.0f);
        }
    }
}

}  // namespace dynsky
