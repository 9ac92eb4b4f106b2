#include "renderer/builtin_scene.h"

#include "renderer/shapes.h"

namespace dynsky {

Scene make_builtin_scene() {
    Scene scene;
    scene.source = "builtin:plaza";
    auto material = [&](const char* name, Color base, float metallic, float roughness) {
        Material m;
        m.name = name, m.base_color = base, m.metallic = metallic, m.roughness = roughness;
        scene.materials.push_back(m);
        return int(scene.materials.size()) - 1;
    };
    int ground = material("wet stone", Color(0.18f, 0.18f, 0.2f), 0.0f, 0.18f);
    int mirror = material("chrome", Color(0.95f, 0.95f, 0.95f), 1.0f, 0.02f);
    int gold = material("brushed gold", Color(1.0f, 0.78f, 0.34f), 1.0f, 0.35f);
    int plaster = material("white plaster", Color(0.8f, 0.78f, 0.74f), 0.0f, 0.9f);
    int brick = material("red brick", Color(0.55f, 0.22f, 0.15f), 0.0f, 0.8f);
    int glass = material("dark glass", Color(0.05f, 0.06f, 0.07f), 0.0f, 0.03f);

    using T = Eigen::Translation3f;
    add_mesh_instance(&scene, make_ground_quad_mesh(60.0f, ground), Eigen::Affine3f::Identity(), "ground");
    add_mesh_instance(&scene, make_sphere_mesh(128, 64, mirror), Eigen::Affine3f(T(0, 1, 0)), "mirror sphere");
    add_mesh_instance(&scene, make_sphere_mesh(96, 48, gold),
                      Eigen::Affine3f(T(2.4f, 0.7f, 1.0f) * Eigen::Scaling(0.7f)), "gold sphere");
    add_mesh_instance(&scene, make_sphere_mesh(96, 48, plaster),
                      Eigen::Affine3f(T(-2.3f, 0.8f, 0.8f) * Eigen::Scaling(0.8f)), "plaster sphere");
    // A tower block behind: brick body with a glass curtain wall facing the camera.
    add_mesh_instance(&scene, make_box_mesh(Vec3(-1.5f, 0, -7), Vec3(1.5f, 9, -4), brick), Eigen::Affine3f::Identity(),
                      "tower");
    add_mesh_instance(&scene, make_box_mesh(Vec3(-1.3f, 0.5f, -4.02f), Vec3(1.3f, 8.5f, -3.98f), glass),
                      Eigen::Affine3f::Identity(), "curtain wall");
    add_mesh_instance(&scene, make_box_mesh(Vec3(3.5f, 0, -5), Vec3(6.5f, 3.5f, -2), plaster),
                      Eigen::Affine3f::Identity(), "house");

    Camera cam;
    cam.name = "plaza";
    cam.yfov = 0.75f;
    Vec3 eye(0.5f, 1.6f, 7.5f), target(0.3f, 1.8f, -2.0f);
    Vec3 f = (target - eye).normalized(), r = f.cross(Vec3::UnitY()).normalized(), u = r.cross(f);
    Eigen::Matrix3f rot;
    rot.col(0) = r, rot.col(1) = u, rot.col(2) = -f;
    cam.camera_to_world = Eigen::Translation3f(eye) * rot;
    scene.cameras.push_back(cam);
    return scene;
}

}  // namespace dynsky
