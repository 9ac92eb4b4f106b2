// Equirectangular (lat-long) panoramas of a sky, so the same skies light Blender, Unreal and
// other renderers that take an HDRI.
//
// Layout (W x H, W = 2H): pixel (c, r), row 0 at the top, has centre (u, v) = ((c + .5) / W, (r + .5) / H),
//   zenith angle theta = pi v  (top row zenith, the horizon between the two middle rows, bottom nadir),
//   azimuth      phi   = 2 pi u - pi / 2, measured from north towards east (CONVENTIONS.md):
//   u = 0.25 north, u = 0.5 (centre column) east, u = 0.75 south, u = 0 and 1 west.
// This is Blender's equirectangular mapping (Cycles' direction_to_equirectangular:
// u = 0.5 - atan2(y, x) / 2 pi, Z up) for a world where north is +Y and east +X, which is where
// Blender's glTF importer puts our north (-Z) and east (+X), so a dynsky latlong used as Blender's
// Environment Texture with the default mapping lights an imported glTF scene from the right side.
// The lower half (the ground) holds a constant colour (default black): a sky image says nothing
// below the horizon.
#pragma once

#include <memory>
#include <string>

#include "sky/sky_image.h"
#include "util/image.h"
#include "util/math.h"

namespace dynsky {

class ProgressBar;

// Direction of a lat-long point (u, v) in [0, 1]^2 and back (u in [0, 1), v in [0, 1]).
Vec3d latlong_direction(double u, double v);
void latlong_uv(const Vec3d& w, double* u, double* v);

// Exact solid angle of a pixel of row r in a W x H lat-long image.
double latlong_pixel_solid_angle(int row, int width, int height);

// Bilinear radiance of a fisheye sky in direction w, using only pixels whose centre lies inside
// the disc (weights renormalised at the rim). Black below the horizon.
Color sample_sky(const SkyImage& sky, const Vec3d& w);

// Bilinear lookup in a lat-long image (wraps in azimuth, clamps at the poles).
Color sample_latlong(const Image& latlong, const Vec3d& w);

// The sky as a W x (W / 2) lat-long image (W even, >= 4). Each pixel averages (weighted by solid
// angle) enough bilinear lookups of the fisheye to see every fisheye pixel it covers, so a sun
// one fisheye pixel wide is neither missed nor doubled and the upper hemisphere's integral is kept.
// Metadata: the sky's time, sun direction and source, plus the layout.
Image sky_to_latlong(const SkyImage& sky, int width, const Color& ground = Color::Zero());

// The inverse, for downloaded HDRIs (Blender's mapping above): a W x (W / 2) lat-long image to a
// canonical fisheye of resolution N. Each fisheye pixel averages (weighted by solid angle)
// enough bilinear lat-long lookups to see every lat-long pixel it covers. lower = false: the sky
// (upper half); lower = true: the ground (lower half) as a fisheye seen from above, the pixel of
// direction (x, y, z) holding the radiance arriving from (x, -y, z).
// progress (may be null) advances by 2 a row of the fisheye.
SkyImage latlong_to_fisheye(const Image& latlong, int resolution, bool lower = false, ProgressBar* progress = nullptr);

// An equirect (2:1) image is a lat-long environment, anything else not.
inline bool is_latlong_shape(int width, int height) { return height > 0 && width == 2 * height; }

// A lat-long environment file (EXR or any format OpenImageIO reads), checked (2:1, finite,
// non-negative) and converted: sky (upper half) and ground (lower half) as fisheyes of
// resolution N (0: the lat-long's height, which keeps its angular resolution at the horizon).
// Throws dynsky::Error naming the file.
struct LatlongEnvironment {
    SkyImage sky, ground;
};
LatlongEnvironment load_latlong_environment(const std::string& path, int resolution = 0);
LatlongEnvironment latlong_environment(const Image& image, const std::string& name, int resolution = 0);
// The checks latlong_environment makes of the pixels (RGB, finite, at least 0, at most 1e9), naming
// the file and the pixel.
void check_latlong_pixels(const Image& image, const std::string& name);

// A sky turned about the zenith: every azimuth (from north towards east) plus `degrees`, its sun
// and filled mask with it. A lat-long turns exactly (its columns roll, to the nearest column); a
// fisheye by a quarter turn exactly (its pixels permuted), by other angles through a lat-long of
// 4N columns and back, both conversions keeping the hemisphere's integral and the sun's energy (a
// bilinear image rotation loses up to half of a one-pixel sun), at the cost of blur (about half the
// pixel-scale detail).
// Returns the turn done (degrees rounded to whole columns: 360 / W).
double turn_latlong(Image* latlong, double degrees);
SkyImage turned_about_zenith(const SkyImage& sky, double degrees);

// How --sky takes a sky file (`render`, `animate`, `compare`, `sky timeline`, `sky predict`):
//   resolution     0  N (--sky-res): both sky and ground come back N x N (a fisheye resampled:
//                     area-averaged down, bilinear up; a lat-long converted at N). 0: a fisheye keeps its own; a
//                     lat-long converts at its height, at most latlong_limit when that is positive
//   latlong_limit  0  see above (kMovingLatlongLimit where the sky moves)
//   turn_deg       0  --sky-turn: turned about the zenith (turned_about_zenith), e.g. to put a
//                     downloaded HDRI's sun where the scene wants it
struct SkyFileOptions {
    int resolution = 0;
    int latlong_limit = 0;
    double turn_deg = 0;
};

// A sky file as --sky takes it: a canonical fisheye (load_sky; *ground = nullptr), or a lat-long
// environment, whose sky is returned and whose ground goes to *ground.
SkyImage load_sky_or_latlong(const std::string& path, std::shared_ptr<SkyImage>* ground,
                             const SkyFileOptions& options = {});

// The largest fisheye a lat-long HDRI becomes, unasked, when the sky moves: every medium step
// works on many full-size fields (an 8192 x 4096 HDRI taken at its height, 4096 px: 4 GB and 30 s
// for one `sky predict` step, the conversion included; 16384 x 8192 would need 16 GB), and the clouds' motion and the networks' correction are
// measured far coarser. `render` converts at the height (the sun's sharpness in still frames).
inline constexpr int kMovingLatlongLimit = 2048;
// The note a command moving a sky prints when it took a lat-long (`sky predict`, `animate`,
// `compare`): its upper half moves as an n x n fisheye; `size_given`: --sky-res chose n (else the
// note names it).
std::string moving_latlong_note(const std::string& path, int n, bool size_given);

}  // namespace dynsky
