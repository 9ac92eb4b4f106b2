#include "sky/hosek_wilkie.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/test_support.h"
#include "util/data_path.h"
#include "util/error.h"

namespace dynsky {
namespace {

constexpr double kDeg = kPiD / 180.0;

std::vector<std::vector<double>> read_csv(const std::string& path) {
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << path;
    std::vector<std::vector<double>> rows;
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        std::vector<double> row;
        std::stringstream ss(line);
        std::string cell;
        while (std::getline(ss, cell, ',')) row.push_back(std::stod(cell));
        rows.push_back(row);
    }
    return rows;
}

// Every vector printed by the reference implementation v1.4a, to 1e-4 relative.
TEST(HosekWilkie, MatchesReferenceSkyVectors) {
    DYNSKY_REQUIRE_SHARED();
    auto rows = read_csv(test::shared_path("sky-models/hosek-wilkie/test_vectors_rgb.csv"));
    ASSERT_GT(rows.size(), 100u);
    double worst = 0, worst_float = 0;
    for (const auto& r : rows) {
        ASSERT_EQ(r.size(), 8u);
        HosekWilkieSky sky(r[0], r[1], r[2] * kDeg);
        double theta = r[3] * kDeg, gamma = r[4] * kDeg;
        Color fast = sky.sky_radiance_rgb(std::cos(theta), gamma, std::cos(gamma));
        for (int c = 0; c < 3; ++c) {
            double expected = r[5 + c];
            double rel = std::abs(sky.sky_radiance(c, theta, gamma) - expected) / std::abs(expected);
            double rel_fast = std::abs(fast[c] - expected) / std::abs(expected);
            worst = std::max(worst, rel);
            worst_float = std::max(worst_float, rel_fast);
            EXPECT_LT(rel, 1e-4) << "T " << r[0] << " albedo " << r[1] << " elevation " << r[2] << " theta " << r[3]
                                 << " gamma " << r[4] << " channel " << c;
            EXPECT_LT(rel_fast, 1e-4) << "fast path, channel " << c;
        }
    }
    std::printf("sky vectors: %zu rows, worst relative error %.3g (float image path %.3g)\n", rows.size(), worst,
                worst_float);
}

TEST(HosekWilkie, MatchesReferenceSolarVectors) {
    DYNSKY_REQUIRE_SHARED();
    auto rows = read_csv(test::shared_path("sky-models/hosek-wilkie/test_vectors_solar.csv"));
    ASSERT_GT(rows.size(), 100u);
    double worst = 0;
    for (const auto& r : rows) {
        ASSERT_EQ(r.size(), 6u);
        HosekWilkieSky sky(r[0], r[1], r[2] * kDeg);
        double value = sky.solar_spectral_radiance(r[3], r[4] * kDeg);
        double rel = std::abs(value - r[5]) / std::abs(r[5]);
        worst = std::max(worst, rel);
        EXPECT_LT(rel, 1e-4) << "T " << r[0] << " elevation " << r[2] << " wavelength " << r[3] << " gamma " << r[4]
                             << ": " << value << " vs " << r[5];
    }
    std::printf("solar vectors: %zu rows, worst relative error %.3g\n", rows.size(), worst);
}

TEST(HosekWilkie, SolarDiscEdgeAndOutside) {
    HosekWilkieSky sky(3, 0.3, 40 * kDeg);
    EXPECT_GT(sky.solar_spectral_radiance(550, 0.0), 1000.0);
    EXPECT_EQ(sky.solar_spectral_radiance(550, kHosekWilkieSolarRadius * 1.001), 0.0);
    EXPECT_EQ(sky.solar_radiance_rgb(kHosekWilkieSolarRadius * 1.001).matrix().norm(), 0.0f);
    // Limb darkening: the edge is dimmer than the centre.
    EXPECT_LT(sky.solar_spectral_radiance(550, kHosekWilkieSolarRadius * 0.99),
              0.6 * sky.solar_spectral_radiance(550, 0.0));
    EXPECT_THROW(sky.solar_spectral_radiance(800, 0.0), Error);
}

// The RGB sun is the spectral sun integrated against the CIE 1931 functions (5 nm table, L held at
// its 720 nm value beyond 720): recompute that sum directly from the spectral function. Out-of-gamut
// (negative) channels of a low sun are desaturated, keeping the luminance.
TEST(HosekWilkie, SolarRgbIsTheCieIntegralOfTheSpectrum) {
    const HosekWilkieData& data = hosek_wilkie_data();
    const Eigen::Matrix3d m = xyz_to_rec709();
    for (double elevation : {2.0, 15.0, 60.0}) {
        for (double turbidity : {2.0, 4.5, 10.0}) {
            HosekWilkieSky sky(turbidity, 0.3, elevation * kDeg);
            for (double g : {0.0, 0.5, 0.9}) {
                double gamma = g * kHosekWilkieSolarRadius;
                Eigen::Vector3d sum = Eigen::Vector3d::Zero();
                for (size_t k = 0; k < data.cie_xyz.size(); ++k) {
                    double lambda = std::min(720.0, data.cie_start_nm + data.cie_step_nm * k);
                    sum += m * data.cie_xyz[k] * sky.solar_spectral_radiance(lambda, gamma) * data.cie_step_nm;
                }
                Color rgb = sky.solar_radiance_rgb(gamma);
                double y = 0.2126 * sum[0] + 0.7152 * sum[1] + 0.0722 * sum[2];
                EXPECT_NEAR(luminance(rgb), y, 1e-5 * y) << elevation << " " << turbidity;
                EXPECT_GE(rgb.minCoeff(), 0.0f);
                if (sum.minCoeff() >= 0) {
                    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[c], sum[c], 1e-5 * sum[c]) << elevation << " " << c;
                } else {
                    EXPECT_LT(elevation, 10.0) << "only a low sun should leave the gamut";
                }
            }
        }
    }
}

TEST(HosekWilkie, SolarIrradianceIsTheDiscIntegral) {
    HosekWilkieSky sky(2.5, 0.3, 50 * kDeg);
    // Midpoint rule in gamma, d omega = 2 pi sin(gamma) d gamma.
    const int n = 20000;
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (int k = 0; k < n; ++k) {
        double gamma = (k + 0.5) / n * kHosekWilkieSolarRadius;
        sum += sky.solar_radiance_rgb(gamma).cast<double>() * 2 * kPiD * std::sin(gamma) *
               (kHosekWilkieSolarRadius / n);
    }
    Color e = sky.solar_irradiance_rgb();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(e[c], sum[c], 2e-4 * sum[c]);
    // Rings add up to the disc.
    Color rings = sky.solar_irradiance_rgb(0, 0.3) + sky.solar_irradiance_rgb(0.3, 0.8) +
                  sky.solar_irradiance_rgb(0.8, 1.0);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rings[c], e[c], 1e-5 * e[c]);
}

TEST(HosekWilkie, CieTableAndMatrix) {
    const HosekWilkieData& data = hosek_wilkie_data();
    ASSERT_EQ(data.cie_xyz.size(), 95u);  // 360..830 nm
    double y_integral = 0;
    for (const auto& xyz : data.cie_xyz) y_integral += xyz.y() * data.cie_step_nm;
    EXPECT_NEAR(y_integral, 106.857, 0.01);  // the CIE's integral of y_bar
    // D65 white maps to equal RGB.
    Eigen::Vector3d white = xyz_to_rec709() * Eigen::Vector3d(0.95047, 1.0, 1.08883);
    EXPECT_NEAR(white.x(), 1.0, 1e-3);
    EXPECT_NEAR(white.y(), 1.0, 1e-3);
    EXPECT_NEAR(white.z(), 1.0, 1e-3);
}

TEST(HosekWilkie, RejectsOutOfRangeParameters) {
    EXPECT_THROW(HosekWilkieSky(0.5, 0.3, 0.5), Error);
    EXPECT_THROW(HosekWilkieSky(10.5, 0.3, 0.5), Error);
    EXPECT_THROW(HosekWilkieSky(3, -0.1, 0.5), Error);
    EXPECT_THROW(HosekWilkieSky(3, 1.1, 0.5), Error);
    EXPECT_THROW(HosekWilkieSky(3, 0.3, -0.01), Error);
    EXPECT_THROW(HosekWilkieSky(NAN, 0.3, 0.5), Error);
    EXPECT_NO_THROW(HosekWilkieSky(1, 0, 0));
    EXPECT_NO_THROW(HosekWilkieSky(10, 1, kPiD / 2));
    try {
        validate_hosek_wilkie_range(12, 0.3);
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("turbidity"), std::string::npos);
    }
}

TEST(HosekWilkie, BrokenTablesGiveClearErrors) {
    namespace fs = std::filesystem;
    std::string dir = test::temp_dir("hw");
    std::string shipped = data_path("sky/data/hosek-wilkie");
    std::string cie = data_path("sky/data/cie/cie1931_2deg_5nm.csv");
    fs::copy_file(shipped + "/solar_spectral.txt", dir + "/solar_spectral.txt");
    // rgb.txt with one number missing from datasetRGB2.
    std::ifstream in(shipped + "/rgb.txt");
    std::ofstream out(dir + "/rgb.txt");
    std::string line;
    bool in_section = false, dropped = false;
    while (std::getline(in, line)) {
        if (line.rfind("# datasetRGB2 ", 0) == 0) in_section = true;
        else if (in_section && !dropped && line[0] != '#') {
            dropped = true;
            continue;
        }
        out << line << "\n";
    }
    out.close();
    try {
        load_hosek_wilkie_data(dir, cie);
        FAIL() << "a short section must be rejected";
    } catch (const Error& e) {
        std::string what = e.what();
        EXPECT_NE(what.find("rgb.txt"), std::string::npos) << what;
        EXPECT_NE(what.find("datasetRGB2"), std::string::npos) << what;
    }
    EXPECT_THROW(load_hosek_wilkie_data(dir + "/missing", cie), Error);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace dynsky
