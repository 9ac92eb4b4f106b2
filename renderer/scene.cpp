#include "renderer/scene.h"

#include "util/error.h"

namespace dynsky {

Bounds3 Scene::world_bounds() const {
    Bounds3 b;
    for (const Instance& inst : instances)
        for (const TriangleMesh& mesh : meshes[size_t(inst.mesh_group)].primitives)
            for (const Vec3& p : mesh.positions) b.extend(inst.transform * p);
    return b;
}

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const Instance& inst : instances)
        for (const TriangleMesh& mesh : meshes[size_t(inst.mesh_group)].primitives) n += mesh.triangle_count();
    return n;
}

const Material& Scene::default_material() {
    static const Material m = [] {
        Material d;
        d.name = "glTF default";
        return d;
    }();
    return m;
}

Camera frame_bounds_camera(const Bounds3& bounds, float aspect_ratio) {
    Camera cam;
    cam.name = "framing camera";
    cam.yfov = 0.7f;
    cam.aspect_ratio = aspect_ratio;
    Vec3 center = bounds.empty() ? Vec3::Zero() : bounds.center();
    // At least a micrometre (a scene of one point still gets a camera), not a millimetre: a model
    // of a few millimetres was framed several times too far out.
    float radius = bounds.empty() ? 1.0f
                                  : std::max(0.5f * bounds.diagonal().norm(),
                                             1e-6f * std::max(1.0f, center.cwiseAbs().maxCoeff()));
    // Look from the south-east and above, far enough that the bounding sphere fits the narrower fov.
    float fov = cam.yfov;
    if (aspect_ratio > 0 && aspect_ratio < 1) fov = 2 * std::atan(std::tan(fov / 2) * aspect_ratio);
    float distance = radius / std::sin(fov / 2) * 1.05f;
    Vec3 dir = Vec3(0.6f, 0.45f, 0.65f).normalized();  // from the centre towards the eye
    Vec3 eye = center + distance * dir;
    Vec3 forward = (center - eye).normalized();
    Vec3 right = forward.cross(Vec3::UnitY()).normalized();
    Vec3 up = right.cross(forward);
    Eigen::Matrix3f rot;
    rot.col(0) = right, rot.col(1) = up, rot.col(2) = -forward;
    cam.camera_to_world = Eigen::Translation3f(eye) * rot;
    return cam;
}

Camera look_at_camera(const Vec3& eye, const Vec3& target, float yfov) {
    if (!eye.allFinite() || !target.allFinite()) throw Error("--look-at: eye and target must be finite");
    if (!(eye.cwiseAbs().maxCoeff() <= kMaxSceneCoordinate && target.cwiseAbs().maxCoeff() <= kMaxSceneCoordinate))
        throw Error(
            "--look-at: eye and target must lie within 1e+08 m of the origin (single precision cannot "
            "resolve a scene from farther out)");
    if (!((target - eye).norm() > 1e-6f * std::max(1.0f, eye.norm())))
        throw Error("--look-at: eye and target are the same point");
    if (!(yfov > 0 && yfov < kPi)) throw Error("--look-at: field of view must be in (0, 180) degrees");
    Camera cam;
    cam.name = "look-at camera";
    cam.yfov = yfov;
    // Up is the world's +Y as seen along the view, down to views a hair from vertical (in double:
    // right = forward x Y keeps its direction as its length goes to 0). Switching to another hint
    // near vertical turned the image half round between two views a degree apart; only a view
    // exactly vertical, which has no such up, takes +Z.
    const Eigen::Vector3d f = (target.cast<double>() - eye.cast<double>()).normalized();
    const double across = std::hypot(f.x(), f.z());
    const Eigen::Vector3d right = across > 1e-12 ? Eigen::Vector3d(-f.z(), 0.0, f.x()) / across
                                                 : f.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d up = right.cross(f);
    Eigen::Matrix3f rot;
    rot.col(0) = right.cast<float>(), rot.col(1) = up.normalized().cast<float>(), rot.col(2) = -f.cast<float>();
    cam.camera_to_world = Eigen::Translation3f(eye) * rot;
    return cam;
}

// Every surface a Lambertian of its base colour (textures and vertex colours kept), as
// tools/cycles/render_cycles.py --override-material lambert does in Cycles: the two renderers then
// share an exact BRDF, which separates geometry and lighting from material models. Emission goes
// too, as it does there.
void override_materials_lambert(Scene* scene) {
    int white = -1;
    for (MeshGroup& group : scene->meshes)
        for (TriangleMesh& mesh : group.primitives)
            if (mesh.material < 0) {
                if (white < 0) {
                    scene->materials.push_back(Scene::default_material());
                    white = int(scene->materials.size()) - 1;
                }
                mesh.material = white;
            }
    for (Material& m : scene->materials)
        m.metallic = 0, m.specular = 0, m.transmission = 0,
        m.emissive = Color::Zero();  // glass too: as Cycles' diffuse
}

}  // namespace dynsky
