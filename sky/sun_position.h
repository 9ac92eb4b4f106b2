// Where the sun is: topocentric zenith and azimuth from a UTC date-time and a place on Earth.
//
// Algorithm: Meeus, "Astronomical Algorithms" (2nd ed., 1998). The sun's geometric longitude is
// the truncated VSOP87 series of Meeus's Appendix III (ch. 32, the planetary theory of
// Bretagnon & Francou 1988; Meeus quotes about 1" accuracy for the truncated series), then
// the IAU 1980 nutation's four largest terms (ch. 22), aberration, the obliquity of the ecliptic
// (ch. 22), apparent sidereal time (ch. 12), the sun's parallax for an observer on the
// ellipsoid (ch. 40) and, optionally, Saemundsson's refraction formula with its pressure and
// temperature correction (ch. 16). TT - UT comes from the Espenak & Meeus (2006) polynomials.
// Measured against PyEphem (full VSOP87) at 1468 random times and places 1950-2050: worst 0.00035
// deg; NREL SPA reference case: +0.00002 deg zenith, +0.00006 deg azimuth (docs/sky.md).
// The input is taken as UT1 (|UT1 - UTC| < 0.9 s, at most 0.004 deg of hour angle).
#pragma once

#include <string>

#include "util/math.h"

namespace dynsky {

// A calendar date-time in UTC (Gregorian calendar).
struct UtcTime {
    int year = 2000, month = 1, day = 1, hour = 0, minute = 0;
    double second = 0.0;
};

// Parses ISO 8601 "YYYY-MM-DDThh:mm[:ss[.fff]]" followed by "Z" or a "+hh:mm" / "-hh:mm" offset
// (the offset is removed, so the result is UTC). A space may replace the "T". Throws
// dynsky::Error naming the text and what is wrong with it (including a missing time zone).
UtcTime parse_utc_time(const std::string& iso8601);

// "2026-06-21T12:00:00Z".
std::string format_utc_time(const UtcTime& t);

// t plus a number of seconds (may be negative or fractional), normalised to a calendar time.
UtcTime add_seconds(const UtcTime& t, double seconds);

// Julian date (UT) of a UTC time.
double julian_date(const UtcTime& t);

// parse_utc_time's time in seconds on one absolute scale (Julian date x 86400): for ordering and
// subtracting times given in any zone. Throws as parse_utc_time does.
double utc_seconds(const std::string& iso8601);

// A place on Earth (WGS84 geodetic). Longitude is east-positive, in [-180, 180].
struct GeoLocation {
    double latitude_deg = 0, longitude_deg = 0, elevation_m = 0;
};

// The sun as seen from a place: topocentric zenith angle (with refraction when asked) and azimuth
// measured from north towards east, in [0, 360), both in degrees.
struct SunPosition {
    double zenith_deg = 0, azimuth_deg = 0;
    // Unit vector to the sun in the world frame (../shared/CONVENTIONS.md: +Y up, north -Z, east +X).
    Vec3d direction() const;
    double elevation_deg() const { return 90.0 - zenith_deg; }
};

// Throws dynsky::Error if the location is out of range (latitude outside [-90, 90], ...).
void validate_location(const GeoLocation& where);

// Sun position at time t. refraction: add the atmospheric refraction for pressure_mbar and
// temperature_c (applied while the true sun is above -1 degree, where the formula holds).
SunPosition compute_sun_position(const UtcTime& t, const GeoLocation& where, bool refraction = true,
                                 double pressure_mbar = 1010, double temperature_c = 10);

// TT - UT in seconds for a decimal year (Espenak & Meeus 2006, "Five Millennium Canon of Solar
// Eclipses", NASA TP-2006-214141; polynomial fits to the observed values up to 2005, a
// projection after).
double delta_t_seconds(double decimal_year);

}  // namespace dynsky
