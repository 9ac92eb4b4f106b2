#include "sky/sun_position.h"

#include <cctype>
#include <cmath>
#include <ctime>
#include <cstdio>

#include "sky/fisheye.h"
#include "util/error.h"
#include "util/parse.h"

namespace dynsky {

namespace {

constexpr double kDeg = kPiD / 180.0;

// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's days_from_civil).
long long days_from_civil(long long y, int m, int d) {
    y -= m <= 2;
    const long long era = (y >= 0 ? y : y - 399) / 400;
    const long long yoe = y - era * 400;
    const long long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    const long long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;
}

void civil_from_days(long long z, int* y, int* m, int* d) {
    z += 719468;
    const long long era = (z >= 0 ? z : z - 146096) / 146097;
    const long long doe = z - era * 146097;
    const long long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
    const long long doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    const long long mp = (5 * doy + 2) / 153;
    *d = int(doy - (153 * mp + 2) / 5 + 1);
    *m = int(mp < 10 ? mp + 3 : mp - 9);
    *y = int(yoe + era * 400 + (*m <= 2));
}

int days_in_month(int y, int m) {
    static const int days[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    return m == 2 && leap ? 29 : days[m - 1];
}

double wrap_degrees(double a) {
    a = std::fmod(a, 360.0);
    return a < 0 ? a + 360.0 : a;
}

}  // namespace

UtcTime parse_utc_time(const std::string& text) {
    auto fail = [&](const std::string& why) -> void {
        throw Error("time '" + text + "': " + why +
                    " (expected ISO 8601 like 2026-06-21T12:00:00Z or 2026-06-21T14:00:00+02:00)");
    };
    size_t pos = 0;
    auto number = [&](int digits, const char* what) {
        int value = 0;
        for (int k = 0; k < digits; ++k, ++pos) {
            if (pos >= text.size() || !std::isdigit((unsigned char)text[pos]))
                fail(std::string("the ") + what + " needs " + std::to_string(digits) + " digits");
            value = value * 10 + (text[pos] - '0');
        }
        return value;
    };
    auto expect = [&](char c, const char* where) {
        if (pos >= text.size() || text[pos] != c) fail(std::string("expected '") + c + "' " + where);
        ++pos;
    };
    UtcTime t;
    t.year = number(4, "year");
    expect('-', "after the year");
    t.month = number(2, "month");
    expect('-', "after the month");
    t.day = number(2, "day");
    if (pos >= text.size() || (text[pos] != 'T' && text[pos] != 't' && text[pos] != ' '))
        fail("expected 'T' between the date and the time of day");
    ++pos;
    t.hour = number(2, "hour");
    expect(':', "after the hour");
    t.minute = number(2, "minute");
    t.second = 0;
    if (pos < text.size() && text[pos] == ':') {
        ++pos;
        t.second = number(2, "second");
        if (pos < text.size() && (text[pos] == '.' || text[pos] == ',')) {
            ++pos;
            double scale = 0.1;
            if (pos >= text.size() || !std::isdigit((unsigned char)text[pos]))
                fail("no digits after the decimal point of the seconds");
            while (pos < text.size() && std::isdigit((unsigned char)text[pos])) {
                t.second += scale * (text[pos] - '0');
                scale *= 0.1;
                ++pos;
            }
        }
    }
    if (t.month < 1 || t.month > 12) fail("month " + std::to_string(t.month) + " is not in 1..12");
    if (t.day < 1 || t.day > days_in_month(t.year, t.month))
        fail("day " + std::to_string(t.day) + " does not exist in " + std::to_string(t.year) + "-" +
             (t.month < 10 ? "0" : "") + std::to_string(t.month));
    if (t.hour > 23) fail("hour " + std::to_string(t.hour) + " is not in 0..23");
    if (t.minute > 59) fail("minute " + std::to_string(t.minute) + " is not in 0..59");
    if (t.second >= 61.0) fail("second is not in 0..60");

    int offset_minutes = 0;
    if (pos >= text.size()) fail("no time zone: append Z for UTC or an offset such as +02:00");
    if (text[pos] == 'Z' || text[pos] == 'z') {
        ++pos;
    } else if (text[pos] == '+' || text[pos] == '-') {
        int sign = text[pos] == '+' ? 1 : -1;
        ++pos;
        int oh = number(2, "offset hours");
        int om = 0;
        if (pos < text.size() && text[pos] == ':') ++pos;
        if (pos < text.size()) om = number(2, "offset minutes");
        if (oh > 18 || om > 59) fail("time zone offset out of range");
        offset_minutes = sign * (oh * 60 + om);
    } else {
        fail(std::string("unexpected '") + text[pos] + "' where the time zone (Z or +hh:mm) should be");
    }
    if (pos != text.size()) fail("unexpected text '" + text.substr(pos) + "' after the time zone");

    // Local time = UTC + offset, so UTC = local - offset. Normalise through minutes since the epoch.
    long long minutes = days_from_civil(t.year, t.month, t.day) * 1440LL + t.hour * 60 + t.minute - offset_minutes;
    long long days = minutes >= 0 ? minutes / 1440 : -((-minutes + 1439) / 1440);
    int minute_of_day = int(minutes - days * 1440);
    civil_from_days(days, &t.year, &t.month, &t.day);
    t.hour = minute_of_day / 60;
    t.minute = minute_of_day % 60;
    return t;
}

std::string format_utc_time(const UtcTime& t) {
    char buf[64];
    double whole;
    double frac = std::modf(t.second, &whole);
    // Milliseconds cut, not rounded: 23:59:59.9996 printed as 23:59:60.000, a second that day has not.
    if (frac > 1e-9)
        std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%06.3fZ", t.year, t.month, t.day, t.hour, t.minute,
                      std::floor(t.second * 1000) / 1000);
    else
        std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02dZ", t.year, t.month, t.day, t.hour, t.minute,
                      int(whole));
    return buf;
}

double julian_date(const UtcTime& t) {
    // JD 2440587.5 is 1970-01-01T00:00 UT.
    return double(days_from_civil(t.year, t.month, t.day)) + 2440587.5 +
           (t.hour + (t.minute + t.second / 60.0) / 60.0) / 24.0;
}

double utc_seconds(const std::string& iso8601) { return julian_date(parse_utc_time(iso8601)) * 86400.0; }

double delta_t_seconds(double y) {
    // Espenak & Meeus (2006), the pieces covering 1800-2150 (the 1900-1920 piece extrapolated to
    // 1800 gave -7.4 h: the sun 0.3 degrees off).
    if (y < 1860) {
        const double t = y - 1800;
        return 13.72 + t * (-0.332447 +
                            t * (0.0068612 +
                                 t * (0.0041116 + t * (-0.00037436 + t * (0.0000121272 +
                                                                          t * (-0.0000001699 + t * 0.000000000875))))));
    }
    if (y < 1900) {
        const double t = y - 1860;
        return 7.62 + t * (0.5737 + t * (-0.251754 + t * (0.01680668 + t * (-0.0004473624 + t / 233174.0))));
    }
    if (y < 1920) {
        double t = y - 1900;
        return -2.79 + 1.494119 * t - 0.0598939 * t * t + 0.0061966 * t * t * t - 0.000197 * t * t * t * t;
    }
    if (y < 1941) {
        double t = y - 1920;
        return 21.20 + 0.84493 * t - 0.076100 * t * t + 0.0020936 * t * t * t;
    }
    if (y < 1961) {
        double t = y - 1950;
        return 29.07 + 0.407 * t - t * t / 233.0 + t * t * t / 2547.0;
    }
    if (y < 1986) {
        double t = y - 1975;
        return 45.45 + 1.067 * t - t * t / 260.0 - t * t * t / 718.0;
    }
    if (y < 2005) {
        double t = y - 2000;
        return 63.86 + 0.3345 * t - 0.060374 * t * t + 0.0017275 * t * t * t + 0.000651814 * t * t * t * t +
               0.00002373599 * t * t * t * t * t;
    }
    if (y < 2050) {
        double t = y - 2000;
        return 62.92 + 0.32217 * t + 0.005589 * t * t;
    }
    double u = (y - 1820) / 100;
    return -20 + 32 * u * u - 0.5628 * (2150 - y);
}

Vec3d SunPosition::direction() const { return fisheye::direction_from_angles(zenith_deg * kDeg, azimuth_deg * kDeg); }

void validate_location(const GeoLocation& where) {
    if (!std::isfinite(where.latitude_deg) || where.latitude_deg < -90 || where.latitude_deg > 90)
        throw Error("latitude " + number_text(where.latitude_deg) + " is not in [-90, 90] degrees");
    // Up to 360 either way: 200 east is 160 west (the hour angle only turns by whole turns), as
    // tools that count longitudes 0..360 write them.
    if (!std::isfinite(where.longitude_deg) || where.longitude_deg < -360 || where.longitude_deg > 360)
        throw Error("longitude " + number_text(where.longitude_deg) +
                    " is not in [-360, 360] degrees (east positive; 0..360 counts as 0..-360 west)");
    if (!std::isfinite(where.elevation_m) || where.elevation_m < -1000 || where.elevation_m > 100000)
        throw Error("elevation " + std::to_string(where.elevation_m) + " m is not in [-1000, 100000] m");
}

namespace {

// VSOP87 periodic terms for the Earth, truncated as in Meeus, "Astronomical Algorithms",
// Appendix III (from Bretagnon & Francou 1988): amplitude A (1e-8 rad or AU), phase B (rad),
// frequency C (rad per Julian millennium). Each series is sum A cos(B + C tau).
struct VsopTerm {
    double a, b, c;
};
const VsopTerm kL0[] = {{175347046, 0, 0},           {3341656, 4.6692568, 6283.07585},
                        {34894, 4.6261, 12566.1517}, {3497, 2.7441, 5753.3849},
                        {3418, 2.8289, 3.5231},      {3136, 3.6277, 77713.7715},
                        {2676, 4.4181, 7860.4194},   {2343, 6.1352, 3930.2097},
                        {1324, 0.7425, 11506.7698},  {1273, 2.0371, 529.691},
                        {1199, 1.1096, 1577.3435},   {990, 5.233, 5884.927},
                        {902, 2.045, 26.298},        {857, 3.508, 398.149},
                        {780, 1.179, 5223.694},      {753, 2.533, 5507.553},
                        {505, 4.583, 18849.228},     {492, 4.205, 775.523},
                        {357, 2.92, 0.067},          {317, 5.849, 11790.629},
                        {284, 1.899, 796.298},       {271, 0.315, 10977.079},
                        {243, 0.345, 5486.778},      {206, 4.806, 2544.314},
                        {205, 1.869, 5573.143},      {202, 2.458, 6069.777},
                        {156, 0.833, 213.299},       {132, 3.411, 2942.463},
                        {126, 1.083, 20.775},        {115, 0.645, 0.98},
                        {103, 0.636, 4694.003},      {102, 0.976, 15720.839},
                        {102, 4.267, 7.114},         {99, 6.21, 2146.17},
                        {98, 0.68, 155.42},          {86, 5.98, 161000.69},
                        {85, 1.3, 6275.96},          {85, 3.67, 71430.7},
                        {80, 1.81, 17260.15},        {79, 3.04, 12036.46},
                        {75, 1.76, 5088.63},         {74, 3.5, 3154.69},
                        {74, 4.68, 801.82},          {70, 0.83, 9437.76},
                        {62, 3.98, 8827.39},         {61, 1.82, 7084.9},
                        {57, 2.78, 6286.6},          {56, 4.39, 14143.5},
                        {56, 3.47, 6279.55},         {52, 0.19, 12139.55},
                        {52, 1.33, 1748.02},         {51, 0.28, 5856.48},
                        {49, 0.49, 1194.45},         {41, 5.37, 8429.24},
                        {41, 2.4, 19651.05},         {39, 6.17, 10447.39},
                        {37, 6.04, 10213.29},        {37, 2.57, 1059.38},
                        {36, 1.71, 2352.87},         {36, 1.78, 6812.77},
                        {33, 0.59, 17789.85},        {30, 0.44, 83996.85},
                        {30, 2.74, 1349.87},         {25, 3.16, 4690.48}};
const VsopTerm kL1[] = {{628331966747, 0, 0},       {206059, 2.678235, 6283.07585},
                        {4303, 2.6351, 12566.1517}, {425, 1.59, 3.523},
                        {119, 5.796, 26.298},       {109, 2.966, 1577.344},
                        {93, 2.59, 18849.23},       {72, 1.14, 529.69},
                        {68, 1.87, 398.15},         {67, 4.41, 5507.55},
                        {59, 2.89, 5223.69},        {56, 2.17, 155.42},
                        {45, 0.4, 796.3},           {36, 0.47, 775.52},
                        {29, 2.65, 7.11},           {21, 5.34, 0.98},
                        {19, 1.85, 5486.78},        {19, 4.97, 213.3},
                        {17, 2.99, 6275.96},        {16, 0.03, 2544.31},
                        {16, 1.43, 2146.17},        {15, 1.21, 10977.08},
                        {12, 2.83, 1748.02},        {12, 3.26, 5088.63},
                        {12, 5.27, 1194.45},        {12, 2.08, 4694},
                        {11, 0.77, 553.57},         {10, 1.3, 6286.6},
                        {10, 4.24, 1349.87},        {9, 2.7, 242.73},
                        {9, 5.64, 951.72},          {8, 5.3, 2352.87},
                        {6, 2.65, 9437.76},         {6, 4.67, 4690.48}};
const VsopTerm kL2[] = {{52919, 0, 0},     {8720, 1.0721, 6283.0758}, {309, 0.867, 12566.152}, {27, 0.05, 3.52},
                        {16, 5.19, 26.3},  {16, 3.68, 155.42},        {10, 0.76, 18849.23},    {9, 2.06, 77713.77},
                        {7, 0.83, 775.52}, {5, 4.66, 1577.34},        {4, 1.03, 7.11},         {4, 3.44, 5573.14},
                        {3, 5.14, 796.3},  {3, 6.05, 5507.55},        {3, 1.19, 242.73},       {3, 6.12, 529.69},
                        {3, 0.31, 398.15}, {3, 2.28, 553.57},         {2, 4.38, 5223.69},      {2, 3.75, 0.98}};
const VsopTerm kL3[] = {{289, 5.844, 6283.076}, {35, 0, 0},         {17, 5.49, 12566.15}, {3, 5.2, 155.42},
                        {1, 4.72, 3.52},        {1, 5.3, 18849.23}, {1, 5.97, 242.73}};
const VsopTerm kL4[] = {{114, 3.142, 0}, {8, 4.13, 6283.08}, {1, 3.84, 12566.15}};
const VsopTerm kL5[] = {{1, 3.14, 0}};
const VsopTerm kB0[] = {{280, 3.199, 84334.662},
                        {102, 5.422, 5507.553},
                        {80, 3.88, 5223.69},
                        {44, 3.7, 2352.87},
                        {32, 4, 1577.34}};
const VsopTerm kB1[] = {{9, 3.9, 5507.55}, {6, 1.73, 5223.69}};
const VsopTerm kR0[] = {{100013989, 0, 0},
                        {1670700, 3.0984635, 6283.07585},
                        {13956, 3.05525, 12566.1517},
                        {3084, 5.1985, 77713.7715},
                        {1628, 1.1739, 5753.3849},
                        {1576, 2.8469, 7860.4194},
                        {925, 5.453, 11506.77},
                        {542, 4.564, 3930.21},
                        {472, 3.661, 5884.927},
                        {346, 0.964, 5507.553},
                        {329, 5.9, 5223.694},
                        {307, 0.299, 5573.143},
                        {243, 4.273, 11790.629},
                        {212, 5.847, 1577.344},
                        {186, 5.022, 10977.079},
                        {175, 3.012, 18849.228},
                        {110, 5.055, 5486.778},
                        {98, 0.89, 6069.78},
                        {86, 5.69, 15720.84},
                        {86, 1.27, 161000.69},
                        {65, 0.27, 17260.15},
                        {63, 0.92, 529.69},
                        {57, 2.01, 83996.85},
                        {56, 5.24, 71430.7},
                        {49, 3.25, 2544.31},
                        {47, 2.58, 775.52},
                        {45, 5.54, 9437.76},
                        {43, 6.01, 6275.96},
                        {39, 5.36, 4694},
                        {38, 2.39, 8827.39},
                        {37, 0.83, 19651.05},
                        {37, 4.9, 12139.55},
                        {36, 1.67, 12036.46},
                        {35, 1.84, 2942.46},
                        {33, 0.24, 7084.9},
                        {32, 0.18, 5088.63},
                        {32, 1.78, 398.15},
                        {28, 1.21, 6286.6},
                        {28, 1.9, 6279.55},
                        {26, 4.59, 10447.39}};
const VsopTerm kR1[] = {{103019, 1.10749, 6283.07585},
                        {1721, 1.0644, 12566.1517},
                        {702, 3.142, 0},
                        {32, 1.02, 18849.23},
                        {31, 2.84, 5507.55},
                        {25, 1.32, 5223.69},
                        {18, 1.42, 1577.34},
                        {10, 5.91, 10977.08},
                        {9, 1.42, 6275.96},
                        {9, 0.27, 5486.78}};
const VsopTerm kR2[] = {{4359, 5.7846, 6283.0758}, {124, 5.579, 12566.152}, {12, 3.14, 0},
                        {9, 3.63, 77713.77},       {6, 1.87, 5573.14},      {3, 5.47, 18849.23}};
const VsopTerm kR3[] = {{145, 4.273, 6283.076}, {7, 3.92, 12566.15}};
const VsopTerm kR4[] = {{4, 2.56, 6283.08}};

template <size_t N>
double vsop_sum(const VsopTerm (&terms)[N], double tau) {
    double s = 0;
    for (const VsopTerm& t : terms) s += t.a * std::cos(t.b + t.c * tau);
    return s;
}

// Geometric ecliptic longitude and latitude of the sun (degrees, FK5, mean equinox of date) and
// its distance (AU). T: Julian centuries (TT) from J2000.0. Meeus ch. 25 ("higher accuracy").
void sun_geometric(double T, double* longitude_deg, double* latitude_deg, double* distance_au) {
    const double tau = T / 10.0;  // Julian millennia
    double L = (vsop_sum(kL0, tau) +
                tau * (vsop_sum(kL1, tau) +
                       tau * (vsop_sum(kL2, tau) +
                              tau * (vsop_sum(kL3, tau) + tau * (vsop_sum(kL4, tau) + tau * vsop_sum(kL5, tau)))))) /
               1e8;
    double B = (vsop_sum(kB0, tau) + tau * vsop_sum(kB1, tau)) / 1e8;
    double R = (vsop_sum(kR0, tau) +
                tau * (vsop_sum(kR1, tau) +
                       tau * (vsop_sum(kR2, tau) + tau * (vsop_sum(kR3, tau) + tau * vsop_sum(kR4, tau))))) /
               1e8;
    // Heliocentric Earth -> geocentric sun, then VSOP87's dynamical ecliptic -> FK5 (Meeus 32.3).
    double theta = wrap_degrees(L / kDeg + 180.0);
    double beta = -B / kDeg;
    double lp = (theta - 1.397 * T - 0.00031 * T * T) * kDeg;
    *longitude_deg = theta - 0.09033 / 3600.0;
    *latitude_deg = beta + 0.03916 / 3600.0 * (std::cos(lp) - std::sin(lp));
    *distance_au = R;
}

}  // namespace

SunPosition compute_sun_position(const UtcTime& t, const GeoLocation& where, bool refraction, double pressure_mbar,
                                 double temperature_c) {
    validate_location(where);
    if (refraction &&
        (!(pressure_mbar > 0 && pressure_mbar <= 2000) || !(temperature_c >= -100 && temperature_c <= 100)))
        throw Error("refraction needs a pressure in (0, 2000] mbar and a temperature in [-100, 100] C");

    const double jd_ut = julian_date(t);
    const double decimal_year = t.year + (t.month - 0.5) / 12.0;
    const double jd_tt = jd_ut + delta_t_seconds(decimal_year) / 86400.0;
    const double T = (jd_tt - 2451545.0) / 36525.0;   // Julian centuries, TT
    const double Tu = (jd_ut - 2451545.0) / 36525.0;  // Julian centuries, UT

    double lon_true, lat_true, R;
    sun_geometric(T, &lon_true, &lat_true, &R);

    // Nutation (IAU 1980, the four largest terms: 0.5" in longitude, 0.1" in obliquity; Meeus ch. 22).
    double omega = (125.04452 - 1934.136261 * T + 0.0020708 * T * T + T * T * T / 450000.0) * kDeg;
    double Ls = (280.4665 + 36000.7698 * T) * kDeg;   // mean longitude of the sun
    double Lm = (218.3165 + 481267.8813 * T) * kDeg;  // mean longitude of the moon
    double dpsi = (-17.20 * std::sin(omega) - 1.32 * std::sin(2 * Ls) - 0.23 * std::sin(2 * Lm) +
                   0.21 * std::sin(2 * omega)) /
                  3600.0;
    double deps = (9.20 * std::cos(omega) + 0.57 * std::cos(2 * Ls) + 0.10 * std::cos(2 * Lm) -
                   0.09 * std::cos(2 * omega)) /
                  3600.0;
    double eps0 = 23.0 + 26.0 / 60.0 + (21.448 - 46.8150 * T - 0.00059 * T * T + 0.001813 * T * T * T) / 3600.0;
    double eps = (eps0 + deps) * kDeg;

    // Apparent longitude: nutation and annual aberration (20.4898" / R).
    double lambda = (lon_true + dpsi - 20.4898 / 3600.0 / R) * kDeg;
    double beta = lat_true * kDeg;
    double alpha = std::atan2(std::sin(lambda) * std::cos(eps) - std::tan(beta) * std::sin(eps), std::cos(lambda));
    double delta = std::asin(std::sin(beta) * std::cos(eps) + std::cos(beta) * std::sin(eps) * std::sin(lambda));

    // Apparent sidereal time at Greenwich (Meeus 12.4 plus the equation of the equinoxes).
    double theta0 = 280.46061837 + 360.98564736629 * (jd_ut - 2451545.0) + 0.000387933 * Tu * Tu -
                    Tu * Tu * Tu / 38710000.0;
    double theta = wrap_degrees(theta0 + dpsi * std::cos(eps)) * kDeg;
    double H = theta + where.longitude_deg * kDeg - alpha;  // local hour angle

    // Parallax: topocentric right ascension and declination (Meeus ch. 40, WGS84-like b/a).
    double phi = where.latitude_deg * kDeg;
    double xi = (8.794 / 3600.0 / R) * kDeg;
    double u = std::atan(0.99664719 * std::tan(phi));
    double rho_sin = 0.99664719 * std::sin(u) + where.elevation_m / 6378140.0 * std::sin(phi);
    double rho_cos = std::cos(u) + where.elevation_m / 6378140.0 * std::cos(phi);
    double d_alpha = std::atan2(-rho_cos * std::sin(xi) * std::sin(H),
                                std::cos(delta) - rho_cos * std::sin(xi) * std::cos(H));
    double delta_top = std::atan2((std::sin(delta) - rho_sin * std::sin(xi)) * std::cos(d_alpha),
                                  std::cos(delta) - rho_cos * std::sin(xi) * std::cos(H));
    double H_top = H - d_alpha;

    // Horizontal coordinates.
    double sin_e = std::sin(phi) * std::sin(delta_top) + std::cos(phi) * std::cos(delta_top) * std::cos(H_top);
    double e0 = std::asin(clamp(sin_e, -1.0, 1.0)) / kDeg;
    double gamma = std::atan2(std::sin(H_top), std::cos(H_top) * std::sin(phi) - std::tan(delta_top) * std::cos(phi));
    double azimuth = wrap_degrees(gamma / kDeg + 180.0);

    // Refraction, Saemundsson (1986) as in Meeus eq. 16.4, scaled by P/1010 * 283/(273 + T).
    // Below -1 degree (where the formula is no longer meant to hold) it decays as 1 / tan of the
    // depression from its value at -1 degree, as NOAA's calculator does below the horizon: cut off
    // there, the elevation jumped 0.67 degrees in an instant and the twilight sky doubled in
    // brightness within seconds, 4-5 minutes from every sunrise and sunset.
    double de = 0;
    if (refraction) {
        const double scale = (pressure_mbar / 1010.0) * (283.0 / (273.0 + temperature_c));
        auto saemundsson = [&](double e) { return scale * 1.02 / (60.0 * std::tan((e + 10.3 / (e + 5.11)) * kDeg)); };
        de = e0 > -1.0 ? saemundsson(e0)
                       : saemundsson(-1.0) * std::tan(1.0 * kDeg) / std::tan(std::min(-e0, 89.0) * kDeg);
    }

    SunPosition s;
    s.zenith_deg = 90.0 - (e0 + de);
    s.azimuth_deg = azimuth;
    return s;
}

UtcTime add_seconds(const UtcTime& t, double seconds) {
    std::tm tm{};
    tm.tm_year = t.year - 1900, tm.tm_mon = t.month - 1, tm.tm_mday = t.day;
    tm.tm_hour = t.hour, tm.tm_min = t.minute, tm.tm_sec = 0;
    double total = t.second + seconds;
    double whole = std::floor(total);
    time_t base = timegm(&tm) + time_t(whole);
    std::tm out{};
    gmtime_r(&base, &out);
    UtcTime r;
    r.year = out.tm_year + 1900, r.month = out.tm_mon + 1, r.day = out.tm_mday;
    r.hour = out.tm_hour, r.minute = out.tm_min, r.second = out.tm_sec + (total - whole);
    return r;
}

}  // namespace dynsky
