#include "sky/hosek_wilkie.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "util/data_path.h"
#include "util/error.h"

namespace dynsky {

namespace {

constexpr int kTurbidities = 10, kControlPoints = 6, kParams = 9, kSolarPieces = 45, kSolarOrder = 4;

// "# NAME COUNT" starts a section; any other '#' line is a comment; other lines hold one number.
std::map<std::string, std::vector<double>> read_sections(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw_file_error(path, "cannot open the Hosek-Wilkie table");
    std::map<std::string, std::vector<double>> sections;
    std::map<std::string, size_t> declared;
    std::string line, current;
    int line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos) continue;
        if (line[0] == '#') {
            std::istringstream words(line.substr(1));
            std::string name, count, extra;
            if (words >> name >> count && !(words >> extra) &&
                count.find_first_not_of("0123456789") == std::string::npos) {
                current = name;
                declared[name] = std::stoul(count);
                sections[name].reserve(declared[name]);
            }
            continue;
        }
        if (current.empty())
            throw_file_error(path, "line " + std::to_string(line_number) +
                                       ": a number before any '# NAME COUNT' section header");
        const char* begin = line.c_str();
        char* end = nullptr;
        double value = std::strtod(begin, &end);
        while (*end == ' ' || *end == '\t') ++end;
        if (end == begin || *end != '\0' || !std::isfinite(value))
            throw_file_error(path, "line " + std::to_string(line_number) + ": '" + line + "' is not a number");
        sections[current].push_back(value);
    }
    for (const auto& [name, count] : declared)
        if (sections[name].size() != count)
            throw_file_error(path, "section " + name + " has " + std::to_string(sections[name].size()) +
                                       " numbers, its header says " + std::to_string(count));
    return sections;
}

std::vector<double> take(std::map<std::string, std::vector<double>>& sections, const std::string& path,
                         const std::string& name, size_t count) {
    auto it = sections.find(name);
    if (it == sections.end()) throw_file_error(path, "no section " + name);
    if (it->second.size() != count)
        throw_file_error(path, "section " + name + " has " + std::to_string(it->second.size()) +
                                   " numbers, the model needs " + std::to_string(count));
    return it->second;
}

void read_cie(const std::string& path, HosekWilkieData* data) {
    std::ifstream in(path);
    if (!in) throw_file_error(path, "cannot open the CIE colour-matching function table");
    std::string line;
    int line_number = 0;
    double previous = -1;
    while (std::getline(in, line)) {
        ++line_number;
        if (line.empty() || line[0] == '#' || line.rfind("wavelength", 0) == 0) continue;
        double w, x, y, z;
        char c1, c2, c3;
        std::istringstream row(line);
        if (!(row >> w >> c1 >> x >> c2 >> y >> c3 >> z) || c1 != ',' || c2 != ',' || c3 != ',')
            throw_file_error(path, "line " + std::to_string(line_number) + ": expected 'wavelength,x,y,z'");
        if (previous < 0) {
            data->cie_start_nm = w;
        } else if (std::abs(w - previous - data->cie_step_nm) > 1e-9) {
            throw_file_error(path, "line " + std::to_string(line_number) + ": wavelengths must rise in 5 nm steps");
        }
        previous = w;
        data->cie_xyz.emplace_back(x, y, z);
    }
    if (data->cie_xyz.size() < 50) throw_file_error(path, "too few rows for a colour-matching function table");
}

// Quintic Bernstein polynomial over 6 control points spaced `stride` apart.
double bernstein5(const double* p, int stride, double s) {
    double t = 1.0 - s;
    return t * t * t * t * t * p[0] + 5 * t * t * t * t * s * p[stride] + 10 * t * t * t * s * s * p[2 * stride] +
           10 * t * t * s * s * s * p[3 * stride] + 5 * t * s * s * s * s * p[4 * stride] +
           s * s * s * s * s * p[5 * stride];
}

// Integer turbidity index (0-based) and weight of the next one, as the reference does it.
void split_turbidity(double turbidity, int* low, double* frac) {
    *low = int(turbidity) - 1;
    *frac = turbidity - (*low + 1);
    if (*low == kTurbidities - 1) {
        *low = kTurbidities - 2;
        *frac = 1.0;
    }
}

// Band index and weight of the next band for a wavelength in [320, 720] nm.
void split_band(double wavelength_nm, int* band, double* frac) {
    double x = (wavelength_nm - 320.0) / 40.0;
    *band = int(x);
    *frac = x - *band;
    if (*band >= kHosekWilkieBands - 1) {
        *band = kHosekWilkieBands - 2;
        *frac = 1.0;
    }
}

// A low sun's spectrum lies outside the Rec.709 gamut (negative blue). Desaturate towards the
// grey of equal luminance just enough to reach the gamut: luminance, so photometric energy, is kept.
Eigen::Array3d desaturate_into_gamut(const Eigen::Array3d& rgb) {
    double y = luminance(rgb[0], rgb[1], rgb[2]);
    if (!(y > 0)) return Eigen::Array3d::Zero();
    double lowest = rgb.minCoeff();
    if (lowest >= 0) return rgb;
    double t = y / (y - lowest);
    return (y + t * (rgb - y)).max(0.0);
}

}  // namespace

HosekWilkieData load_hosek_wilkie_data(const std::string& folder, const std::string& cie_csv) {
    HosekWilkieData data;
    std::string rgb_path = folder + "/rgb.txt";
    auto rgb = read_sections(rgb_path);
    for (int c = 0; c < 3; ++c) {
        data.sky_params[c] = take(rgb, rgb_path, "datasetRGB" + std::to_string(c + 1),
                                  2 * kTurbidities * kControlPoints * kParams);
        data.sky_radiance[c] = take(rgb, rgb_path, "datasetRGBRad" + std::to_string(c + 1),
                                    2 * kTurbidities * kControlPoints);
    }
    std::string solar_path = folder + "/solar_spectral.txt";
    auto solar = read_sections(solar_path);
    for (int b = 0; b < kHosekWilkieBands; ++b) {
        std::string nm = std::to_string(320 + 40 * b);
        data.solar[b] = take(solar, solar_path, "solarDataset" + nm, kTurbidities * kSolarPieces * kSolarOrder);
        auto ld = take(solar, solar_path, "limbDarkeningDataset" + nm, 6);
        std::copy(ld.begin(), ld.end(), data.limb_darkening[b].begin());
    }
    read_cie(cie_csv, &data);
    return data;
}

const HosekWilkieData& hosek_wilkie_data() {
    static const HosekWilkieData data = load_hosek_wilkie_data(data_path("sky/data/hosek-wilkie"),
                                                               data_path("sky/data/cie/cie1931_2deg_5nm.csv"));
    return data;
}

void validate_hosek_wilkie_range(double turbidity, double albedo) {
    if (!(turbidity >= 1.0 && turbidity <= 10.0))
        throw Error("turbidity " + std::to_string(turbidity) +
                    " is outside the Hosek-Wilkie model's range [1, 10] (2-3: very clear, 10: hazy)");
    if (!(albedo >= 0.0 && albedo <= 1.0))
        throw Error("ground albedo " + std::to_string(albedo) + " is outside [0, 1]");
}

Eigen::Matrix3d xyz_to_rec709() {
    Eigen::Matrix3d m;
    m << 3.2404542, -1.5371385, -0.4985314,  //
        -0.9692660, 1.8760108, 0.0415560,    //
        0.0556434, -0.2040259, 1.0572252;
    return m;
}

HosekWilkieSky::HosekWilkieSky(double turbidity, double albedo, double sun_elevation, const HosekWilkieData& data)
    : turbidity_(turbidity), albedo_(albedo), elevation_(sun_elevation), data_(&data) {
    validate_hosek_wilkie_range(turbidity, albedo);
    if (!(sun_elevation >= 0.0 && sun_elevation <= kPiD / 2 + 1e-12))
        throw Error("sun elevation " + std::to_string(sun_elevation * 180 / kPiD) +
                    " deg is outside the Hosek-Wilkie model's range [0, 90] deg");
    elevation_ = std::min(sun_elevation, kPiD / 2);

    // ArHosekSkyModel_CookConfiguration / CookRadianceConfiguration: Bernstein in
    // (elevation / (pi/2))^(1/3), lerp between integer turbidities and albedo 0 / 1.
    const int int_turbidity = int(turbidity);
    const double turbidity_rem = turbidity - int_turbidity;
    const double s = std::pow(elevation_ / (kPiD / 2), 1.0 / 3.0);
    const int albedo_stride = kTurbidities * kControlPoints * kParams;
    for (int c = 0; c < 3; ++c) {
        const double* params = data.sky_params[c].data();
        const double* rad = data.sky_radiance[c].data();
        for (int i = 0; i < kParams; ++i) {
            const double* low = params + kControlPoints * kParams * (int_turbidity - 1) + i;
            double v = (1 - albedo) * (1 - turbidity_rem) * bernstein5(low, kParams, s) +
                       albedo * (1 - turbidity_rem) * bernstein5(low + albedo_stride, kParams, s);
            if (int_turbidity < kTurbidities) {
                const double* high = low + kControlPoints * kParams;
                v += (1 - albedo) * turbidity_rem * bernstein5(high, kParams, s) +
                     albedo * turbidity_rem * bernstein5(high + albedo_stride, kParams, s);
            }
            config_[c][i] = v;
        }
        const double* low = rad + kControlPoints * (int_turbidity - 1);
        double r = (1 - albedo) * (1 - turbidity_rem) * bernstein5(low, 1, s) +
                   albedo * (1 - turbidity_rem) * bernstein5(low + kTurbidities * kControlPoints, 1, s);
        if (int_turbidity < kTurbidities) {
            const double* high = low + kControlPoints;
            r += (1 - albedo) * turbidity_rem * bernstein5(high, 1, s) +
                 albedo * turbidity_rem * bernstein5(high + kTurbidities * kControlPoints, 1, s);
        }
        scale_[c] = r;
    }

    // arhosekskymodel_sr_internal: piecewise cubic in elevation, 45 pieces on a cubic grid, the 4
    // coefficients stored highest order first and read backwards.
    int t_low;
    double t_frac;
    split_turbidity(turbidity, &t_low, &t_frac);
    int pos = int(std::pow(2.0 * elevation_ / kPiD, 1.0 / 3.0) * kSolarPieces);
    if (pos > kSolarPieces - 1) pos = kSolarPieces - 1;
    const double break_x = std::pow(double(pos) / kSolarPieces, 3.0) * (kPiD / 2);
    const double x = elevation_ - break_x;
    auto piece = [&](int band, int t) {
        const double* coefs = data.solar[band].data() + (kSolarOrder * kSolarPieces * t + kSolarOrder * (pos + 1) - 1);
        double res = 0, x_exp = 1;
        for (int i = 0; i < kSolarOrder; ++i) {
            res += x_exp * *coefs--;
            x_exp *= x;
        }
        return res;
    };
    for (int b = 0; b < kHosekWilkieBands; ++b)
        solar_centre_[b] = (1 - t_frac) * piece(b, t_low) + t_frac * piece(b, t_low + 1);

    // Spectral -> RGB: rgb(mu) = sum_k M xyz(lambda_k) L(lambda_k, mu) d lambda, with L linear in the
    // bands (as the model interpolates) and held at its 720 nm value beyond the model's range (the
    // colour-matching functions are < 0.3% of their peak there).
    const Eigen::Matrix3d m = xyz_to_rec709();
    for (auto& k : rgb_limb_) k.setZero();
    for (size_t k = 0; k < data.cie_xyz.size(); ++k) {
        double lambda = data.cie_start_nm + data.cie_step_nm * k;
        double w = std::clamp(lambda, 320.0, 720.0);
        int band;
        double frac;
        split_band(w, &band, &frac);
        double centre = (1 - frac) * solar_centre_[band] + frac * solar_centre_[band + 1];
        Eigen::Array3d weight = (m * data.cie_xyz[k]).array() * data.cie_step_nm * centre;
        for (int j = 0; j < 6; ++j)
            rgb_limb_[j] += weight *
                            ((1 - frac) * data.limb_darkening[band][j] + frac * data.limb_darkening[band + 1][j]);
    }
}

double HosekWilkieSky::sky_radiance(int channel, double theta, double gamma) const {
    const double* p = config_[channel];
    const double cos_gamma = std::cos(gamma), cos_theta = std::cos(theta);
    const double exp_m = std::exp(p[4] * gamma);
    const double ray_m = cos_gamma * cos_gamma;
    const double mie_m = (1.0 + cos_gamma * cos_gamma) / std::pow(1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma, 1.5);
    const double zenith = std::sqrt(cos_theta);
    return (1.0 + p[0] * std::exp(p[1] / (cos_theta + 0.01))) *
           (p[2] + p[3] * exp_m + p[5] * ray_m + p[6] * mie_m + p[7] * zenith) * scale_[channel];
}

Color HosekWilkieSky::sky_radiance_rgb(double cos_theta, double gamma, double cos_gamma) const {
    cos_theta = std::clamp(cos_theta, 0.0, 1.0);
    const double zenith = std::sqrt(cos_theta);
    const double inv_horizon = 1.0 / (cos_theta + 0.01);
    const double ray_m = cos_gamma * cos_gamma;
    Color out;
    for (int c = 0; c < 3; ++c) {
        const double* p = config_[c];
        const double base = 1.0 + p[8] * p[8] - 2.0 * p[8] * cos_gamma;
        const double mie_m = (1.0 + ray_m) / (base * std::sqrt(base));
        double v = (1.0 + p[0] * std::exp(p[1] * inv_horizon)) *
                   (p[2] + p[3] * std::exp(p[4] * gamma) + p[5] * ray_m + p[6] * mie_m + p[7] * zenith) * scale_[c];
        out[c] = float(std::max(v, 0.0));
    }
    return out;
}

double HosekWilkieSky::solar_spectral_radiance(double wavelength_nm, double gamma) const {
    if (!(wavelength_nm >= 320.0 && wavelength_nm <= 720.0))
        throw Error("wavelength " + std::to_string(wavelength_nm) + " nm is outside the solar model's 320..720 nm");
    const double sin_r = std::sin(kHosekWilkieSolarRadius);
    const double sin_g = std::sin(gamma);
    const double sc2 = 1.0 - sin_g * sin_g / (sin_r * sin_r);
    if (std::abs(gamma) > kHosekWilkieSolarRadius || sc2 < 0.0) return 0.0;
    const double mu = std::sqrt(sc2);
    int band;
    double frac;
    split_band(wavelength_nm, &band, &frac);
    double direct = (1 - frac) * solar_centre_[band] + frac * solar_centre_[band + 1];
    double darkening = 0, mu_k = 1;
    for (int j = 0; j < 6; ++j, mu_k *= mu)
        darkening += ((1 - frac) * data_->limb_darkening[band][j] + frac * data_->limb_darkening[band + 1][j]) * mu_k;
    return direct * darkening;
}

Color HosekWilkieSky::solar_radiance_rgb(double gamma) const {
    const double sin_r = std::sin(kHosekWilkieSolarRadius);
    const double sin_g = std::sin(gamma);
    const double sc2 = 1.0 - sin_g * sin_g / (sin_r * sin_r);
    if (std::abs(gamma) > kHosekWilkieSolarRadius || sc2 < 0.0) return Color::Zero();
    const double mu = std::sqrt(sc2);
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    double mu_k = 1;
    for (int j = 0; j < 6; ++j, mu_k *= mu) sum += rgb_limb_[j] * mu_k;
    return desaturate_into_gamut(sum).cast<float>();
}

Color HosekWilkieSky::solar_irradiance_rgb(double s0, double s1) const {
    // d omega = pi sin^2(R) d(s^2) / cos(gamma) with s = sin(gamma) / sin(R); the 1/cos(gamma) factor
    // is below 1 + 1e-5 on the disc and dropped. With u = 1 - s^2 = mu^2, the integral of mu^j is
    // [u^(j/2 + 1) / (j/2 + 1)] between 1 - s1^2 and 1 - s0^2.
    s0 = std::clamp(s0, 0.0, 1.0);
    s1 = std::clamp(s1, 0.0, 1.0);
    const double sin_r = std::sin(kHosekWilkieSolarRadius);
    const double u_hi = 1.0 - s0 * s0, u_lo = 1.0 - s1 * s1;
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (int j = 0; j < 6; ++j) {
        double e = j / 2.0 + 1.0;
        sum += rgb_limb_[j] * ((std::pow(u_hi, e) - std::pow(u_lo, e)) / e);
    }
    return desaturate_into_gamut(kPiD * sin_r * sin_r * sum).cast<float>();
}

Color HosekWilkieSky::solar_irradiance_rgb() const { return solar_irradiance_rgb(0.0, 1.0); }

}  // namespace dynsky
