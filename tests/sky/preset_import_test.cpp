// Imports by a camera preset (sky/preset_import.h) of photographs with no mask files beside them:
// the preset's own obstruction geometry must hide what the imager's masks hide.
#include "sky/preset_import.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "sky/fisheye.h"
#include "sky/hdr_recovery.h"
#include "tests/test_support.h"

namespace dynsky {
namespace {

namespace fs = std::filesystem;

// The photographs of a shared set copied, every `step`-th, into a fresh folder laid out as the set
// (images/), without its masks.
std::vector<std::pair<std::string, std::string>> copy_photos(const std::string& set, const std::string& root,
                                                             int step) {
    const fs::path from = test::shared_path("skies/" + set + "/images");
    const fs::path to = fs::path(root) / set / "images";
    fs::create_directories(to);
    std::vector<fs::path> photos;
    for (const auto& e : fs::directory_iterator(from)) photos.push_back(e.path());
    std::sort(photos.begin(), photos.end());
    std::vector<std::pair<std::string, std::string>> out;  // original, copy
    for (size_t k = 0; k < photos.size(); k += size_t(step)) {
        fs::copy_file(photos[k], to / photos[k].filename(), fs::copy_options::overwrite_existing);
        out.emplace_back(photos[k].string(), (to / photos[k].filename()).string());
    }
    return out;
}

struct Share {
    double filled = 0;  // of the disc
    long long disc = 0;
};

Share filled_share(const ImportedPhoto& p) {
    Share s;
    long long filled = 0;
    for (int j = 0; j < p.sky.resolution; ++j)
        for (int i = 0; i < p.sky.resolution; ++i)
            if (p.sky.in_disc(i, j)) ++s.disc, filled += p.not_sky[size_t(j) * p.sky.resolution + i];
    s.filled = s.disc ? double(filled) / double(s.disc) : 0;
    return s;
}

double filled_iou(const ImportedPhoto& a, const ImportedPhoto& b) {
    long long both = 0, either = 0;
    for (size_t p = 0; p < a.not_sky.size(); ++p)
        both += a.not_sky[p] && b.not_sky[p], either += a.not_sky[p] || b.not_sky[p];
    return either ? double(both) / double(either) : 1.0;
}

double angle_deg(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPiD; }

// Every frame of the three shared TSI sets, copied without tsi_cloudmask/: the preset hides the
// arm, the housing and the band at the sun's azimuth. The filled share lies within the issue's
// 13-15 % (the mask-based import's range is printed beside it), the filled pixels agree with the
// mask-based import's (IoU), and the restored sun is the computed one, not the band's glare.
// In-sample: the geometry was measured on every 5th mask of these same three sets (no other TSI
// day is shared), so the IoU bounds sit just under what that fit reached (0.958 mean, 0.947 worst):
// they catch a geometry or band that drifted, not a new day's.
TEST(PresetImport, TsiWithoutMasksFillsArmHousingAndBandOnEveryFrame) {
    DYNSKY_REQUIRE_SHARED();
    const int n = 256;
    const std::string root = test::temp_dir("preset_tsi");
    for (const std::string set :
         {"arm_tsi_sgp_20170524", "arm_tsi_sgp_20170524_clear_morning", "arm_tsi_sgp_20170524_overcast_dusk"}) {
        // Every frame; every 4th under the sanitizers (the plain run's longest test, 70 s).
        const auto photos = copy_photos(set, root, test::run_size(1, 4));
        ASSERT_GT(photos.size(), test::run_size(100u, 25u)) << set;
        double lo = 1, hi = 0, mask_lo = 1, mask_hi = 0, iou_sum = 0, iou_min = 1, sun_worst = 0;
        int compared = 0, suns = 0;
        for (size_t k = 0; k < photos.size(); ++k) {
            const auto& [original, copy] = photos[k];
            PresetImportPlan plan = plan_preset_import("arm-tsi", copy, n);
            ASSERT_FALSE(plan.mask_found) << copy;
            ASSERT_TRUE(plan.params.shadow_band.has_value()) << copy;
            // The share does not depend on the fill; the sun test does (every 20th frame).
            plan.params.inpaint = k % size_t(test::run_size(20, 5)) == 0;
            ImportedPhoto imported = import_photo(copy, plan.params);
            const Share s = filled_share(imported);
            lo = std::min(lo, s.filled), hi = std::max(hi, s.filled);
            EXPECT_GE(s.filled, 0.13) << copy;
            EXPECT_LE(s.filled, 0.15) << copy;
            PresetImportPlan with_mask = plan_preset_import("arm-tsi", original, n);
            if (with_mask.mask_found) {
                with_mask.params.inpaint = false;
                ImportedPhoto masked = import_photo(original, with_mask.params);
                const Share m = filled_share(masked);
                mask_lo = std::min(mask_lo, m.filled), mask_hi = std::max(mask_hi, m.filled);
                const double iou = filled_iou(imported, masked);
                iou_sum += iou, iou_min = std::min(iou_min, iou), ++compared;
            }
            if (plan.params.inpaint) {
                HdrCalibrationParams hp;
                hp.time = parse_utc_time(plan.time);
                hp.location = plan.location;
                hp.sun_search_deg = plan.preset.sun_search_deg;
                HdrCalibrationReport report;
                recover_hdr(imported, hp, &report);
                if (report.sun_elevation_deg > 2) {
                    sun_worst = std::max(sun_worst, angle_deg(report.used_sun, report.computed_sun));
                    ++suns;
                }
            }
        }
        std::printf(
            "%s: %zu frames without masks fill %.1f-%.1f %% of the disc (with the imager's masks %.1f-%.1f %%, %d "
            "frames); filled pixels agree with the mask-based import at IoU %.3f mean, %.3f worst; restored sun at "
            "most %.2f deg from the computed one (%d frames)\n",
            set.c_str(), photos.size(), 100 * lo, 100 * hi, 100 * mask_lo, 100 * mask_hi, compared,
            compared ? iou_sum / compared : 0.0, iou_min, sun_worst, suns);
        if (compared) {
            EXPECT_GT(iou_sum / compared, 0.95) << set;
            EXPECT_GT(iou_min, 0.93) << set;
        }
        EXPECT_LT(sun_worst, 0.5) << set << ": the sun must be restored where it is computed, not on the glare";
    }
    fs::remove_all(root);
}

// The Mobotix without background_mask.png beside its photographs: the preset's horizon profile
// hides the masts and railings the mask hides; the share stays near the mask-based import's.
// The band follows the sun at the place used: a TSI imported with --lat/--lon of another site had
// its band at the preset site's sun (14 degrees off at longitude -90; at 40 N 3 W the azimuth of a
// sun below the horizon there) while the sun was restored where the given place has it.
TEST(PresetImport, TsiShadowBandFollowsTheSunOfThePlaceGiven) {
    const std::string photo = "/nowhere/tsi_sgpC1_20170524170000Z.jpg";  // only its name is read
    const UtcTime t = parse_utc_time("2017-05-24T17:00:00Z");
    const PresetImportPlan at_site = plan_preset_import("arm-tsi", photo, 64, "", false);
    ASSERT_TRUE(at_site.params.shadow_band);
    EXPECT_NEAR(at_site.params.shadow_band->azimuth_deg, compute_sun_position(t, at_site.location).azimuth_deg, 1e-9);
    for (const GeoLocation place : {GeoLocation{36.6, -90.0, 0}, GeoLocation{40.0, -3.0, 600}}) {
        const PresetImportPlan plan = plan_preset_import("arm-tsi", photo, 64, "", false, place);
        ASSERT_TRUE(plan.params.shadow_band);
        EXPECT_NEAR(plan.params.shadow_band->azimuth_deg, compute_sun_position(t, place).azimuth_deg, 1e-9);
        EXPECT_GT(std::abs(plan.params.shadow_band->azimuth_deg - at_site.params.shadow_band->azimuth_deg), 5.0);
    }
}

// A TSI photograph whose name gives no time (renamed, or only the JPEG of a download) had its
// band left in the sky: "detected as a dark object", it was not (the band is grey, about as bright
// as a deep blue sky). The band is found in the photograph as the darkest, greyest strip of its
// shape: on the three shared TSI sets, copied under names without a time and without masks, it is
// found in nearly every photograph, near the sun's azimuth at the original name's time, and the
// pixels filled are nearly those of the import with the time.
TEST(PresetImport, TsiWithoutATimeFindsItsBandInThePhotograph) {
    DYNSKY_REQUIRE_SHARED();
    const int n = 128;
    const std::string root = test::temp_dir("preset_tsi_untimed");
    for (const std::string set :
         {"arm_tsi_sgp_20170524", "arm_tsi_sgp_20170524_clear_morning", "arm_tsi_sgp_20170524_overcast_dusk"}) {
        const auto photos = copy_photos(set, root, test::run_size(5, 25));
        double worst = 0, contrast = 0, iou_min = 1;
        int found = 0, right = 0;
        for (size_t k = 0; k < photos.size(); ++k) {
            const auto& [original, copy] = photos[k];
            PresetImportPlan timed = plan_preset_import("arm-tsi", copy, n);
            timed.params.inpaint = false;
            const ImportedPhoto with_time = import_photo(copy, timed.params);
            const std::string untimed =
                (fs::path(copy).parent_path() / ("photo" + std::to_string(k) + ".jpg")).string();
            fs::rename(copy, untimed);
            PresetImportPlan plan = plan_preset_import("arm-tsi", untimed, n);
            ASSERT_TRUE(plan.time.empty()) << untimed;
            ASSERT_TRUE(plan.params.shadow_band && plan.params.shadow_band->find_in_photo) << untimed;
            plan.params.inpaint = false;
            const ImportedPhoto imported = import_photo(untimed, plan.params);
            if (!imported.shadow_band_found) continue;
            ++found;
            double off = std::abs(imported.shadow_band_found->azimuth_deg - timed.params.shadow_band->azimuth_deg);
            off = std::min(off, 360 - off);
            worst = std::max(worst, off);
            contrast = std::max(contrast, imported.shadow_band_found->contrast);
            const double iou = filled_iou(imported, with_time);
            iou_min = std::min(iou_min, iou);
            if (off < 5 && iou > 0.85) ++right;
            else
                std::printf("  %s: found %.1f deg from the sun's azimuth, strip %.0f %% of the sky beside it\n",
                            original.c_str(), off, 100 * imported.shadow_band_found->contrast);
        }
        std::printf(
            "%s: band found in %d of %zu photographs without a time, at most %.2f deg from the sun's "
            "azimuth (strip at most %.0f %% of the sky beside it); filled pixels against the timed import's: "
            "IoU at least %.3f\n",
            set.c_str(), found, photos.size(), worst, 100 * contrast, iou_min);
        // Where one is missed or misplaced (a dark cloud street beside a clipped sun), a warning or the
        // azimuth says so; the test allows one photograph in twenty.
        EXPECT_GE(right, int(0.95 * double(photos.size()))) << set;
    }
    fs::remove_all(root);
}

TEST(PresetImport, MobotixWithoutMaskFillsItsHorizonObjects) {
    DYNSKY_REQUIRE_SHARED();
    const int n = 256;
    const std::string root = test::temp_dir("preset_mobotix");
    const auto photos = copy_photos("mobotix_sophia_20200812_morning", root, 20);
    double lo = 1, hi = 0, mask_lo = 1, mask_hi = 0, iou_min = 1, iou_sum = 0, covered_min = 1;
    int compared = 0;
    for (const auto& [original, copy] : photos) {
        PresetImportPlan plan = plan_preset_import("mobotix", copy, n);
        ASSERT_FALSE(plan.mask_found) << copy;
        plan.params.inpaint = false;
        ImportedPhoto imported = import_photo(copy, plan.params);
        PresetImportPlan with_mask = plan_preset_import("mobotix", original, n);
        ASSERT_TRUE(with_mask.mask_found) << original;
        with_mask.params.inpaint = false;
        ImportedPhoto masked = import_photo(original, with_mask.params);
        const Share s = filled_share(imported), m = filled_share(masked);
        lo = std::min(lo, s.filled), hi = std::max(hi, s.filled);
        mask_lo = std::min(mask_lo, m.filled), mask_hi = std::max(mask_hi, m.filled);
        const double iou = filled_iou(imported, masked);
        iou_sum += iou, iou_min = std::min(iou_min, iou), ++compared;
        // Every pixel the mask-based import fills is filled without the mask too (nearly).
        long long in_mask = 0, covered = 0;
        for (size_t p = 0; p < masked.not_sky.size(); ++p)
            if (masked.not_sky[p]) ++in_mask, covered += imported.not_sky[p];
        covered_min = std::min(covered_min, in_mask ? double(covered) / double(in_mask) : 1.0);
    }
    std::printf(
        "mobotix: %d frames without the mask fill %.1f-%.1f %% of the disc (with it %.1f-%.1f %%); IoU %.3f mean, "
        "%.3f worst; %.1f %% of the mask-based filled pixels covered at worst\n",
        compared, 100 * lo, 100 * hi, 100 * mask_lo, 100 * mask_hi, iou_sum / compared, iou_min, 100 * covered_min);
    EXPECT_GT(covered_min, 0.97);
    EXPECT_GT(iou_min, 0.85);
    EXPECT_LT(hi, mask_hi + 0.05);
    fs::remove_all(root);
}

}  // namespace
}  // namespace dynsky
