#include "renderer/shapes.h"

namespace dynsky {

TriangleMesh make_sphere_mesh(int segments, int rings, int material) {
    TriangleMesh m;
    m.material = material;
    for (int r = 0; r <= rings; ++r) {
        float v = float(r) / rings, theta = v * kPi;
        for (int s = 0; s <= segments; ++s) {
            float u = float(s) / segments, phi = u * 2 * kPi;
            Vec3 p(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
            m.positions.push_back(p);
            m.normals.push_back(p);
            m.texcoords[0].push_back(Vec2(u, v));
            Vec3 t(-std::sin(phi), 0, -std::cos(phi));  // dP/du direction
            m.tangents.push_back(Vec4(t.x(), t.y(), t.z(), 1));
        }
    }
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            uint32_t a = r * (segments + 1) + s, b = a + segments + 1;
            // Counter-clockwise seen from outside.
            if (r != 0) m.indices.insert(m.indices.end(), {a, b, a + 1});
            if (r != rings - 1) m.indices.insert(m.indices.end(), {a + 1, b, b + 1});
        }
    return m;
}

TriangleMesh make_ground_quad_mesh(float size, int material) {
    TriangleMesh m;
    m.material = material;
    float h = size / 2;
    m.positions = {Vec3(-h, 0, -h), Vec3(-h, 0, h), Vec3(h, 0, h), Vec3(h, 0, -h)};
    m.normals.assign(4, Vec3(0, 1, 0));
    m.texcoords[0] = {Vec2(0, 0), Vec2(0, size), Vec2(size, size), Vec2(size, 0)};
    m.tangents.assign(4, Vec4(1, 0, 0, 1));
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

TriangleMesh make_box_mesh(const Vec3& lo, const Vec3& hi, int material) {
    TriangleMesh m;
    m.material = material;
    const Vec3 n[6] = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1)};
    Vec3 c = 0.5f * (lo + hi), e = 0.5f * (hi - lo);
    for (int f = 0; f < 6; ++f) {
        Vec3 nn = n[f], t, b;
        orthonormal_basis(nn, &t, &b);
        // Snap the basis to axes so faces are exact rectangles.
        t = Vec3(std::round(t.x()), std::round(t.y()), std::round(t.z()));
        b = nn.cross(t);
        uint32_t base = uint32_t(m.positions.size());
        const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
        for (int k = 0; k < 4; ++k) {
            Vec3 p = c + (nn + su[k] * t + sv[k] * b).cwiseProduct(e);
            m.positions.push_back(p);
            m.normals.push_back(nn);
            m.texcoords[0].push_back(Vec2(0.5f * (su[k] + 1), 0.5f * (1 - sv[k])));
            m.tangents.push_back(Vec4(t.x(), t.y(), t.z(), 1));
        }
        // t x b = n, so (0,1,2) is counter-clockwise seen from outside.
        m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
    return m;
}

int add_mesh_instance(Scene* scene, TriangleMesh mesh, const Eigen::Affine3f& transform, const std::string& name) {
    MeshGroup g;
    g.name = name;
    g.primitives.push_back(std::move(mesh));
    scene->meshes.push_back(std::move(g));
    Instance inst;
    inst.mesh_group = int(scene->meshes.size()) - 1;
    inst.transform = transform;
    scene->instances.push_back(inst);
    return int(scene->instances.size()) - 1;
}

}  // namespace dynsky
