// The sky every subcommand makes when the user names no place, time or weather: one definition,
// so `render`, `animate`, `compare`, `sky timeline`, `sky predict`, `sky procedural`, `sky clear` and
// `sky sun` agree
// (an option means the same thing everywhere, with the same default).
//
// Defaults:
//   start time      2026-06-21T16:00:00Z  a summer afternoon (the sun follows the clock from there)
//   place           48.8566 N, 2.3522 E    Paris
//   turbidity       3                      a clear day
//   cloud coverage  0.5                    procedural cumulus
//   cloud evolution 900 s                  time for the cumulus shapes to change completely
//   wind            from 270 deg at 12 m/s, clouds at 1500 m (fair-weather cumulus): what moves
//                   the procedural sky and, with no previous frame, the clouds of any input sky
#pragma once

namespace dynsky::default_sky {

inline constexpr const char* kStartTime = "2026-06-21T16:00:00Z";
inline constexpr double kLatitudeDeg = 48.8566;
inline constexpr double kLongitudeDeg = 2.3522;
inline constexpr double kTurbidity = 3.0;
inline constexpr double kCoverage = 0.5;
inline constexpr double kCloudEvolutionS = 900.0;
inline constexpr double kWindFromDeg = 270.0;
inline constexpr double kWindSpeedMps = 12.0;
inline constexpr double kCloudHeightM = 1500.0;

}  // namespace dynsky::default_sky
