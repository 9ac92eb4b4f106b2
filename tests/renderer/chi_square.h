// Pearson's chi-square goodness-of-fit test for sample histograms against expected counts,
// the check pbrt (Chi2Test) and Mitsuba (chi2.py) run on their samplers.
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace dynsky::test {

struct ChiSquareResult {
    double statistic = 0;
    int dof = 0;
    double p_value = 1;
    std::string summary() const {
        return "chi2 = " + std::to_string(statistic) + ", dof = " + std::to_string(dof) +
               ", p = " + std::to_string(p_value);
    }
};

// Bins with expected count below min_expected are pooled into one (as pbrt does).
inline ChiSquareResult chi_square_test(const std::vector<double>& observed, const std::vector<double>& expected,
                                       double min_expected = 5.0) {
    ChiSquareResult r;
    double pooled_obs = 0, pooled_exp = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < min_expected) {
            pooled_obs += observed[i], pooled_exp += expected[i];
            continue;
        }
        double d = observed[i] - expected[i];
        r.statistic += d * d / expected[i];
        ++r.dof;
    }
    if (pooled_exp > 0) {
        double d = pooled_obs - pooled_exp;
        r.statistic += d * d / std::max(pooled_exp, 1e-12);
        ++r.dof;
    }
    r.dof -= 1;
    if (r.dof <= 0) return r;
    // Wilson-Hilferty: (X/k)^(1/3) is close to normal with mean 1 - 2/(9k), variance 2/(9k).
    double k = r.dof;
    double z = (std::cbrt(r.statistic / k) - (1 - 2 / (9 * k))) / std::sqrt(2 / (9 * k));
    r.p_value = 0.5 * std::erfc(z / std::sqrt(2.0));
    return r;
}

}  // namespace dynsky::test
