#include "renderer/material_eval.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace dynsky {
namespace {

void expect_vec3(const Vec3& got, const Vec3& want, float tol = 1e-5f) {
    EXPECT_NEAR((got - want).norm(), 0.0f, tol) << "got (" << got.transpose() << "), want (" << want.transpose() << ")";
}
void expect_color(const Color& got, const Color& want, float tol = 1e-6f) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], tol) << "channel " << c;
}

// A linear (not sRGB) texture of one RGBA value everywhere.
int add_constant_texture(Scene* scene, const Vec4& rgba) {
    scene->textures.push_back(std::make_shared<Texture>("constant", 1, 1,
                                                        std::vector<float>{rgba[0], rgba[1], rgba[2], rgba[3]}, false,
                                                        TextureWrap::Repeat, TextureWrap::Repeat,
                                                        TextureFilter::Nearest));
    return int(scene->textures.size()) - 1;
}

// A hit on the z = 0 plane facing +z, with tangent +x (right-handed), at uv (0.25, 0.75).
SurfaceHit flat_hit(const Material* m) {
    SurfaceHit hit;
    hit.position = Vec3(0, 0, 0);
    hit.geometric_normal = hit.shading_normal = Vec3(0, 0, 1);
    hit.tangent = Vec4(1, 0, 0, 1);
    hit.texcoord[0] = Vec2(0.25f, 0.75f);
    hit.texcoord[1] = Vec2(0.8f, 0.1f);
    hit.material = m;
    return hit;
}

const Vec3 kUp(0, 0, 1);

TEST(MaterialEval, FactorsAloneAndTheVertexColourMultiply) {
    Scene scene;
    Material m;
    m.base_color = Color(0.5f, 0.25f, 1.0f);
    m.metallic = 0.3f, m.roughness = 0.6f, m.specular = 0.7f;
    m.emissive = Color(2, 0, 0);
    SurfaceHit hit = flat_hit(&m);
    hit.color = Vec4(0.5f, 1.0f, 0.2f, 1.0f);
    ShadingPoint sp = evaluate_material(scene, hit, kUp);
    expect_color(sp.base_color, Color(0.25f, 0.25f, 0.2f));
    EXPECT_FLOAT_EQ(sp.metallic, 0.3f);
    EXPECT_FLOAT_EQ(sp.roughness, 0.6f);
    EXPECT_FLOAT_EQ(sp.specular, 0.7f);
    expect_color(sp.emission, Color(2, 0, 0));
    // No normal map: the frame is the hit's own (tangent +x, bitangent +y, normal +z).
    expect_vec3(sp.normal, kUp);
    expect_vec3(sp.geometric_normal, kUp);
    expect_vec3(sp.tangent, Vec3(1, 0, 0));
    expect_vec3(sp.bitangent, Vec3(0, 1, 0));
}

TEST(MaterialEval, TexturesMultiplyTheirFactorsChannelByChannel) {
    Scene scene;
    Material m;
    m.base_color = Color(0.5f, 1.0f, 0.8f);
    m.base_color_texture.texture = add_constant_texture(&scene, Vec4(0.5f, 0.25f, 0.5f, 1));
    m.metallic = 0.5f, m.roughness = 0.8f;
    // glTF: roughness in G, metallic in B; R (occlusion in packed ORM textures) is not used.
    m.metallic_roughness_texture.texture = add_constant_texture(&scene, Vec4(0.1f, 0.5f, 0.25f, 1));
    m.emissive = Color(4, 2, 0);
    m.emissive_texture.texture = add_constant_texture(&scene, Vec4(0.5f, 0.25f, 1.0f, 1));
    m.occlusion_texture.texture = add_constant_texture(&scene, Vec4(0, 0, 0, 1));  // ignored by a path tracer
    SurfaceHit hit = flat_hit(&m);
    ShadingPoint sp = evaluate_material(scene, hit, kUp);
    expect_color(sp.base_color, Color(0.25f, 0.25f, 0.4f));
    EXPECT_FLOAT_EQ(sp.roughness, 0.4f);
    EXPECT_FLOAT_EQ(sp.metallic, 0.125f);
    expect_color(sp.emission, Color(2, 0.5f, 0));
}

TEST(MaterialEval, AnEmissiveTextureWithoutAnEmissiveFactorEmitsNothing) {
    Scene scene;
    Material m;
    m.emissive_texture.texture = add_constant_texture(&scene, Vec4(1, 1, 1, 1));
    ShadingPoint sp = evaluate_material(scene, flat_hit(&m), kUp);
    expect_color(sp.emission, Color(0, 0, 0));
}

TEST(MaterialEval, TexturesAreLookedUpThroughTheirUvSetAndTransform) {
    // A 2 x 2 texture: texel (x, y) has R = x, G = y (nearest), so the value shows which texel uv hit.
    Scene scene;
    scene.textures.push_back(
        std::make_shared<Texture>("quadrants", 2, 2, std::vector<float>{0, 0, 1, 1, 1, 0, 1, 1, 0, 1, 1, 1, 1, 1, 1, 1},
                                  false, TextureWrap::Repeat, TextureWrap::Repeat, TextureFilter::Nearest));
    Material m;
    m.base_color_texture.texture = 0;
    SurfaceHit hit = flat_hit(&m);  // uv0 (0.25, 0.75): texel (0, 1); uv1 (0.8, 0.1): texel (1, 0)
    expect_color(evaluate_material(scene, hit, kUp).base_color, Color(0, 1, 1));
    m.base_color_texture.texcoord = 1;
    expect_color(evaluate_material(scene, hit, kUp).base_color, Color(1, 0, 1));
    // KHR_texture_transform: an offset of (0.5, 0) moves uv1 to (1.3, 0.1), which repeats to texel (0, 0).
    m.base_color_texture.uv_transform(0, 2) = 0.5f;
    EXPECT_NEAR(texture_uv(m.base_color_texture, hit).x(), 1.3f, 1e-6f);
    EXPECT_NEAR(texture_uv(m.base_color_texture, hit).y(), 0.1f, 1e-6f);
    expect_color(evaluate_material(scene, hit, kUp).base_color, Color(0, 0, 1));
}

// A shading normal whose mirror reflection of the viewer goes below the true surface is bent
// towards the geometric normal just enough to lift it out (and no further); one that is fine stays.
TEST(MaterialEval, AShadingNormalIsBentOnlyAsFarAsItsReflectionNeeds) {
    const Vec3 ng(0, 0, 1);
    const Vec3 wo = Vec3(-0.8f, 0, 0.6f).normalized();
    const Vec3 mild = Vec3(0.1f, 0, 1).normalized();
    EXPECT_TRUE(lifted_shading_normal(ng, wo, mild).isApprox(mild));
    for (const float tilt_deg : {50.0f, 70.0f, 85.0f}) {
        const float a = tilt_deg * float(kPi) / 180;
        const Vec3 ns(std::sin(a), 0, std::cos(a));  // tilted away from the viewer
        const Vec3 r0 = 2 * ns.dot(wo) * ns - wo;
        ASSERT_LT(ng.dot(r0), 0) << tilt_deg << ": the test's reflection should start below the surface";
        const Vec3 n = lifted_shading_normal(ng, wo, ns);
        const Vec3 r = 2 * n.dot(wo) * n - wo;
        EXPECT_NEAR(n.norm(), 1, 1e-5f);
        EXPECT_GE(ng.dot(r), 0.01f - 1e-4f) << tilt_deg;
        EXPECT_LT(ng.dot(r), 0.02f) << tilt_deg << ": bent further than needed";
        EXPECT_GT(n.dot(wo), 0) << tilt_deg;
        EXPECT_NEAR(n.y(), 0, 1e-6f) << "stays in the plane of ns and ng";
    }
}

TEST(MaterialEval, BothNormalsTurnToTheViewersSide) {
    Scene scene;
    Material m;
    SurfaceHit hit = flat_hit(&m);
    ShadingPoint sp = evaluate_material(scene, hit, Vec3(0, 0.6f, -0.8f));  // seen from below
    expect_vec3(sp.geometric_normal, -kUp);
    expect_vec3(sp.normal, -kUp);
    // Still an orthonormal frame with normal = tangent x bitangent, tangent along the hit's.
    expect_vec3(sp.tangent.cross(sp.bitangent), sp.normal);
    expect_vec3(sp.tangent, Vec3(1, 0, 0));
    expect_vec3(sp.to_local(Vec3(0, 0.6f, -0.8f)), Vec3(0, -0.6f, 0.8f));
    expect_vec3(sp.to_world(sp.to_local(Vec3(0.36f, 0.48f, 0.8f))), Vec3(0.36f, 0.48f, 0.8f));
}

TEST(MaterialEval, NormalMapTiltsTheNormalInTheTangentFrame) {
    Scene scene;
    Material m;
    // Tangent-space (0.6, 0, 0.8), encoded as (n + 1) / 2.
    m.normal_texture.texture = add_constant_texture(&scene, Vec4(0.8f, 0.5f, 0.9f, 1));
    SurfaceHit hit = flat_hit(&m);
    Vec3 wo = Vec3(0, 0, 1);
    expect_vec3(evaluate_material(scene, hit, wo).normal, Vec3(0.6f, 0, 0.8f));
    // scale multiplies x and y before normalising: (0.3, 0, 0.8).
    m.normal_texture.scale = 0.5f;
    expect_vec3(evaluate_material(scene, hit, wo).normal, Vec3(0.3f, 0, 0.8f).normalized());
    // A tilt along y follows the bitangent, whose sign is the tangent's handedness.
    m.normal_texture.scale = 1.0f;
    scene.textures[0] = std::make_shared<Texture>("n", 1, 1, std::vector<float>{0.5f, 0.8f, 0.9f, 1}, false);
    ShadingPoint sp = evaluate_material(scene, hit, wo);
    expect_vec3(sp.normal, Vec3(0, 0.6f, 0.8f));
    expect_vec3(sp.tangent.cross(sp.bitangent), sp.normal);
    EXPECT_NEAR(sp.tangent.dot(sp.normal), 0.0f, 1e-6f);
    hit.tangent.w() = -1;
    expect_vec3(evaluate_material(scene, hit, wo).normal, Vec3(0, -0.6f, 0.8f));
    // The flat encoding (0.5, 0.5, 1) leaves the normal alone.
    scene.textures[0] = std::make_shared<Texture>("flat", 1, 1, std::vector<float>{0.5f, 0.5f, 1, 1}, false);
    expect_vec3(evaluate_material(scene, hit, wo).normal, kUp);
}

TEST(MaterialEval, NormalMapIsIgnoredWithoutTangentsOrWhenItFacesAway) {
    Scene scene;
    Material m;
    m.normal_texture.texture = add_constant_texture(&scene, Vec4(0.8f, 0.5f, 0.9f, 1));
    SurfaceHit hit = flat_hit(&m);
    hit.tangent = Vec4::Zero();  // no tangents: no tangent space to decode the map in
    expect_vec3(evaluate_material(scene, hit, kUp).normal, kUp);
    // A mapped normal below the surface, tangent-space (0.6, 0, -0.8): ignored.
    hit = flat_hit(&m);
    scene.textures[0] = std::make_shared<Texture>("under", 1, 1, std::vector<float>{0.8f, 0.5f, 0.1f, 1}, false);
    expect_vec3(evaluate_material(scene, hit, kUp).normal, kUp);
}

TEST(MaterialEval, AShadingNormalThatCannotSeeTheViewerIsBentUntilItDoes) {
    Scene scene;
    Material m;
    SurfaceHit hit = flat_hit(&m);
    // Interpolated normal tilted 60 degrees towards +x; a viewer at grazing angle on the -x side
    // is above the surface but behind the shading normal: bent towards the geometric normal until
    // it sees the viewer and reflects it above the surface (lifted_shading_normal).
    hit.shading_normal = Vec3(std::sqrt(0.75f), 0, 0.5f);
    Vec3 wo = Vec3(-0.95f, 0, 0.1f).normalized();
    ASSERT_LT(hit.shading_normal.dot(wo), 0);
    ShadingPoint sp = evaluate_material(scene, hit, wo);
    EXPECT_GT(sp.normal.dot(wo), 0);
    EXPECT_GE(kUp.dot(2 * sp.normal.dot(wo) * sp.normal - wo), std::min(0.9f * kUp.dot(wo), 0.01f) - 1e-4f);
    expect_vec3(sp.geometric_normal, kUp);
    // Seen from where it faces, the interpolated normal is kept.
    sp = evaluate_material(scene, hit, hit.shading_normal);
    expect_vec3(sp.normal, hit.shading_normal);
    EXPECT_NEAR(sp.tangent.dot(sp.normal), 0.0f, 1e-6f);
    EXPECT_NEAR(sp.bitangent.dot(sp.normal), 0.0f, 1e-6f);
    EXPECT_NEAR(sp.tangent.norm(), 1.0f, 1e-6f);
}

}  // namespace
}  // namespace dynsky
