#include "util/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unistd.h>

#include "util/atomic_file.h"
#include "util/color.h"
#include "util/error.h"
#include "util/image_input.h"
#include "util/parse.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string file_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

bool is_hidden_file(const std::string& path) {
    const std::string name = fs::path(path).filename().string();
    return !name.empty() && name[0] == '.';
}

int Image::channel_index(const std::string& name) const {
    for (size_t i = 0; i < channel_names.size(); ++i)
        if (channel_names[i] == name) return int(i);
    return -1;
}

std::string image_size_problem(long long width, long long height, long long channels) {
    if (width <= 0 || height <= 0 || channels <= 0) return "image has no pixels";
    if (width > kMaxImageSide || height > kMaxImageSide || channels > kMaxImageChannels ||
        width * height > kMaxImagePixels || width * height * channels > kMaxImageValues)
        return "image is " + std::to_string(width) + " x " + std::to_string(height) + " with " +
               std::to_string(channels) +
               " channels, beyond what dynsky reads (each side at most 16384, at most 2^28 pixels, 2^29 values and "
               "64 channels; docs/input-limits.md)";
    return "";
}

void check_image_size(const std::string& name, long long width, long long height, long long channels) {
    if (std::string problem = image_size_problem(width, height, channels); !problem.empty())
        throw_file_error(name, problem);
}

namespace {

// The shortest text that reads back as the value; a float's value widened to double (an exposure)
// as the float it was ("0.3", not "0.300000011920929").
std::string shortest_number_text(double v) {
    const bool from_float = std::isfinite(v) && double(float(v)) == v;
    for (int digits = 6; digits <= 17; ++digits) {
        const std::string s = number_text(v, digits);
        const double back = std::strtod(s.c_str(), nullptr);
        if (from_float ? float(back) == float(v) : back == v) return s;
    }
    return number_text(v, 17);
}

// libjpeg fills a file cut short with grey and only warns, which OpenImageIO does not report: walk
// the markers to the end-of-image marker instead. Returns "" when it is there, else the problem.
std::string jpeg_truncation(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t n = b.size();
    if (n < 4 || b[0] != 0xFF || b[1] != 0xD8) return "no JPEG start-of-image marker";
    size_t i = 2;
    while (i + 1 < n) {
        if (b[i] != 0xFF) return "corrupt JPEG: no marker at byte " + std::to_string(i);
        const unsigned char m = b[i + 1];
        if (m == 0xFF) {  // fill byte before a marker
            ++i;
            continue;
        }
        if (m == 0xD9) return "";                     // end of image
        if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {  // TEM, RSTn: no length
            i += 2;
            continue;
        }
        if (i + 3 >= n) break;
        const size_t length = size_t(b[i + 2]) << 8 | b[i + 3];
        if (length < 2) return "corrupt JPEG: bad segment length at byte " + std::to_string(i);
        i += 2 + length;
        if (m == 0xDA)  // start of scan: entropy-coded data (FF only as FF 00 or RSTn) up to the next marker
            while (i + 1 < n && !(b[i] == 0xFF && b[i + 1] != 0x00 && !(b[i + 1] >= 0xD0 && b[i + 1] <= 0xD7))) ++i;
    }
    return "the JPEG is cut short (" + std::to_string(n) +
           " bytes, no end-of-image marker): a truncated download or copy?";
}

// A PNG's chunks must all lie inside the file, up to its IEND chunk. libpng reports a file cut
// short from OpenImageIO's read callback by a longjmp that skips the callback's C++ destructors
// (a leak in the system library), and names no file: a truncated PNG is found here first, and
// never reaches the decoder. Returns "" for a complete chunk sequence, else the problem.
std::string png_truncation(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const size_t n = b.size();
    size_t i = 8;  // after the signature
    while (i + 8 <= n) {
        const size_t length = size_t(b[i]) << 24 | size_t(b[i + 1]) << 16 | size_t(b[i + 2]) << 8 | b[i + 3];
        if (length > 0x7FFFFFFFu)
            return "corrupt PNG: chunk length " + std::to_string(length) + " at byte " + std::to_string(i);
        if (n - i - 8 < length + 4) break;  // data and CRC
        if (std::memcmp(&b[i + 4], "IEND", 4) == 0) return "";
        i += 12 + length;
    }
    return "the PNG is cut short (" + std::to_string(n) +
           " bytes, no complete IEND chunk): a truncated download "
           "or copy?";
}

// A Radiance file (its magic checked by the caller) whose header names a pixel format OpenImageIO
// does not read (XYZE): said as such, not as the reader's "no FORMAT specifier found". "" else.
std::string radiance_format_problem(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    // The header's lines up to the blank one (at most 64 of at most 1 KB: a header, not pixels).
    char buffer[1024];
    in.getline(buffer, sizeof buffer);  // the magic line
    for (int k = 0; k < 64 && in.getline(buffer, sizeof buffer) && buffer[0] != '\0'; ++k)
        if (const std::string line = buffer; line.rfind("FORMAT=", 0) == 0 && line.find("xyze") != std::string::npos)
            return "a Radiance file of XYZE pixels (" + line +
                   "): dynsky reads RGBE ones (FORMAT=32-bit_rle_rgbe); convert it, e.g. with Radiance's "
                   "ra_xyze -r IN.hdr OUT.hdr";
    return "";
}

}  // namespace

bool has_jpeg_signature(const std::string& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;  // a FIFO would block: the reader says what it is
    unsigned char head[3] = {};
    std::ifstream in(path, std::ios::binary);
    return in.read(reinterpret_cast<char*>(head), 3) && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF;
}

std::string image_file_problem(const std::string& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) return "no such file";
    if (fs::is_directory(path, ec)) return "is a directory, not an image";
    // A FIFO or device would block or never end: images are read from regular files only.
    if (!fs::is_regular_file(path, ec)) return "not a regular file (a FIFO or a device?)";
    // Unreadable (permissions): said as such, not as "not an OpenEXR file" by the reader.
    // Its first bytes, read once, say which of the checks below applies.
    unsigned char head[8] = {};
    size_t got = 0;
    if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
        got = std::fread(head, 1, sizeof head, f);
        std::fclose(f);
    } else {
        return std::string("cannot be opened: ") + std::strerror(errno);
    }
    static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (got == 8 && std::memcmp(head, png_signature, 8) == 0) return png_truncation(path);
    if (got >= 6 && (std::memcmp(head, "#?RADI", 6) == 0 || std::memcmp(head, "#?RGBE", 6) == 0))
        return radiance_format_problem(path);
    return "";
}

bool is_black_everywhere(const Image& image) {
    return std::all_of(image.pixels.begin(), image.pixels.end(), [](float v) { return v == 0.0f; });
}

bool made_earlier_with(const std::vector<std::string>& files, const std::string& key_name, const std::string& key) {
    try {
        for (size_t k = 0; k < files.size(); ++k) {
            const Image image = read_image(files[k]);
            if (k == 0) {
                const auto it = image.metadata.strings.find(key_name);
                if (it == image.metadata.strings.end() || it->second != key) return false;
            }
            if (first_non_finite(image) >= 0) return false;
        }
        return !files.empty();
    } catch (const Error&) {
        return false;  // missing, cut short or unreadable: made again
    }
}

long first_non_finite(const Image& image) {
    for (size_t i = 0; i < image.pixels.size(); ++i)
        if (!std::isfinite(image.pixels[i])) return long(i);
    return -1;
}

std::string non_finite_pixel_text(const Image& image, long i) {
    const long c = std::max(1, image.channels), w = std::max(1, image.width), p = i / c;
    return "pixel (" + std::to_string(p % w) + ", " + std::to_string(p / w) + ") is " +
           (std::isnan(image.pixels[size_t(i)]) ? "NaN" : "infinite");
}

std::vector<std::string> image_header_strings(const std::string& path, const std::vector<std::string>& names) {
    std::vector<std::string> values(names.size());
    if (!image_file_problem(path).empty()) return values;
    ImageFileInput in(path);
    if (!in) return values;
    for (size_t k = 0; k < names.size(); ++k) values[k] = in->spec().get_string_attribute(names[k]);
    return values;
}

std::optional<double> image_header_number(const std::string& path, const std::string& name) {
    if (!image_file_problem(path).empty()) return std::nullopt;
    ImageFileInput in(path);
    if (!in) return std::nullopt;
    const OIIO::ParamValue* p = in->spec().find_attribute(name);
    if (!p) return std::nullopt;
    double d = 0;
    // As read_image takes numbers: floats, ints and doubles.
    if (p->type() == OIIO::TypeDesc::FLOAT) d = p->get_float();
    else if (p->type() == OIIO::TypeDesc::INT) d = p->get_int();
    else if (!(p->type() == OIIO::TypeDesc::DOUBLE && in->spec().getattribute(name, OIIO::TypeDesc::DOUBLE, &d)))
        return std::nullopt;
    if (!std::isfinite(d)) return std::nullopt;
    return d;
}

Image read_image(const std::string& path, DataWindow part) {
    if (std::string why = image_file_problem(path); !why.empty()) throw_file_error(path, why);
    ImageFileInput in(path);
    if (!in) {
        const std::string& why = in.error();
        throw_file_error(path, "not a readable image" + (why.empty() ? std::string() : " (" + why + ")"));
    }
    const OIIO::ImageSpec spec = in->spec();
    // Sizes come from the header: check them before anything is allocated.
    check_image_size(path, spec.width, spec.height, spec.nchannels);
    if (spec.depth > 1) throw_file_error(path, "is a volume image (depth " + std::to_string(spec.depth) + ")");
    const bool whole = spec.x == spec.full_x && spec.y == spec.full_y && spec.width == spec.full_width &&
                       spec.height == spec.full_height;
    const bool inside = spec.x >= spec.full_x && spec.y >= spec.full_y &&
                        spec.x + spec.width <= spec.full_x + spec.full_width &&
                        spec.y + spec.height <= spec.full_y + spec.full_height;
    if (!whole && !(part == DataWindow::PartAllowed && inside))
        throw_file_error(path, "its pixels (data window " + std::to_string(spec.width) + "x" +
                                   std::to_string(spec.height) + " at " + std::to_string(spec.x) + "," +
                                   std::to_string(spec.y) + ") do not cover its image (display window " +
                                   std::to_string(spec.full_width) + "x" + std::to_string(spec.full_height) + " at " +
                                   std::to_string(spec.full_x) + "," + std::to_string(spec.full_y) +
                                   "): which part is meant? Write it with matching windows (oiiotool FILE "
                                   "--fullpixels -o OUT.exr to use the pixels, --croptofull for the image)");
    if (in->seek_subimage(1, 0)) {
        int parts = 2;
        while (parts < 1000 && in->seek_subimage(parts, 0)) ++parts;
        throw_file_error(path, "has " + std::to_string(parts) +
                                   " parts (a multi-part EXR or multi-page file): dynsky reads single-part images "
                                   "only; write the part you mean to its own file (oiiotool FILE --subimage N -o "
                                   "PART.exr)");
    }
    (void)in->geterror();  // seeking past the last part may leave a message
    if (!in->seek_subimage(0, 0)) throw_file_error(path, "cannot read its first part: " + in->geterror());
    Image image(spec.width, spec.height, spec.nchannels);
    if (!whole) {
        image.origin_x = spec.x - spec.full_x, image.origin_y = spec.y - spec.full_y;
        image.full_width = spec.full_width, image.full_height = spec.full_height;
    }
    image.file_format = in->format_name();
    image.file_pixel_type = spec.format.c_str();
    bool read = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()) && !in->has_error();
    if (!read) {
        // Some readers (WebP) cannot go back to the first image once asked for a second: read it
        // from a fresh open before calling the file broken.
        (void)in->geterror();
        in.reopen();
        read = in && in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()) &&
               !in->has_error();
    }
    if (!read) {
        std::string why = in ? in->geterror() : in.error();
        throw_file_error(path, "could not decode pixels (truncated or corrupt?)" +
                                   (why.empty() ? std::string() : ": " + why));
    }
    for (const std::string& name : spec.channelnames) image.channel_names.push_back(name);
    if (image.file_format == "jpeg")
        if (std::string why = jpeg_truncation(path); !why.empty()) throw_file_error(path, why);
    for (const auto& p : spec.extra_attribs) {
        std::string name = p.name().string();
        if (p.type() == OIIO::TypeDesc::STRING) image.metadata.strings[name] = p.get_string();
        else if (p.type() == OIIO::TypeDesc::FLOAT) image.metadata.numbers[name] = p.get_float();
        // An int (as `oiiotool --attrib NAME 10` writes a whole number) read as 0 through get_float().
        else if (p.type() == OIIO::TypeDesc::INT) image.metadata.numbers[name] = p.get_int();
        // EXIF's short and long integers (Orientation, ...) come as unsigned and 16-bit types.
        else if (p.type() == OIIO::TypeDesc::UINT || p.type() == OIIO::TypeDesc::UINT16 ||
                 p.type() == OIIO::TypeDesc::INT16)
            image.metadata.numbers[name] = p.get_int();
        else if (p.type() == OIIO::TypeDesc::DOUBLE) {
            double d;  // exactly: get_float() would round it
            if (spec.getattribute(name, OIIO::TypeDesc::DOUBLE, &d)) image.metadata.numbers[name] = d;
        }
    }
    // The primaries the file says its pixels are in (OpenEXR's float[8] attribute).
    Chromaticities primaries;
    if (spec.getattribute("chromaticities", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 8), primaries.data()))
        image.chromaticities = primaries;
    in->close();
    // Radiance files record in EXPOSURE what was multiplied into their pixels (pfilt, hdrgen's
    // exposure changes): the radiance is the pixel over it.
    if (image.file_format == "hdr") {
        const auto e = image.metadata.numbers.find("hdr:exposure");
        if (e != image.metadata.numbers.end() && std::isfinite(e->second) && e->second > 0 && e->second != 1) {
            const float inverse = float(1.0 / e->second);
            for (float& v : image.pixels) v *= inverse;
            e->second = 1;
        }
    }
    return image;
}

int apply_orientation(Image& image) {
    const auto it = image.metadata.numbers.find("Orientation");
    if (it == image.metadata.numbers.end()) return 1;
    const int orientation = int(it->second);
    if (orientation < 2 || orientation > 8 || double(orientation) != it->second || image.empty()) return 1;
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
    // OpenImageIO 2.4's reorient transposes for 7 and transverses for 5; EXIF (and jpegtran,
    // Pillow's exif_transpose) define 5 as the transpose, 7 as the transverse: ask for the other.
    spec.attribute("Orientation", orientation == 5 ? 7 : orientation == 7 ? 5 : orientation);
    const OIIO::ImageBuf source(spec, image.pixels.data());
    const OIIO::ImageBuf turned = OIIO::ImageBufAlgo::reorient(source);
    if (turned.has_error()) throw Error("cannot turn the image by its EXIF orientation: " + turned.geterror());
    const OIIO::ImageSpec& t = turned.spec();
    std::vector<float> pixels(image.pixels.size());
    if (!turned.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, pixels.data()))
        throw Error("cannot turn the image by its EXIF orientation: " + turned.geterror());
    image.width = t.width, image.height = t.height, image.pixels = std::move(pixels);
    it->second = 1;
    return orientation;
}

void write_image(const std::string& path, const Image& image) { write_file_atomic(path, encode_image(path, image)); }

std::string encode_image(const std::string& path, const Image& image) {
    if (image.empty()) throw_file_error(path, "refusing to write an empty image");
    std::string ext = file_extension(path);
    bool is_exr = ext == ".exr";
    bool is_ldr = ext == ".png" || ext == ".jpg" || ext == ".jpeg";
    if (!is_exr && !is_ldr) throw_file_error(path, "unsupported output extension '" + ext + "' (use .exr or .png)");

    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         is_exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (is_exr) spec.attribute("compression", "zip");
    if (is_exr && image.full_width > 0) {  // a part of a larger image (a render region)
        if (image.origin_x < 0 || image.origin_y < 0 || image.origin_x + image.width > image.full_width ||
            image.origin_y + image.height > image.full_height)
            throw_file_error(path, "the pixels do not lie inside the image they are said to be part of");
        spec.x = image.origin_x, spec.y = image.origin_y;
        spec.full_x = spec.full_y = 0;
        spec.full_width = image.full_width, spec.full_height = image.full_height;
    }
    // OpenImageIO stamps an EXR with the wall-clock time (capDate) unless DateTime is set; an empty
    // one writes none, so a file depends only on its pixels and metadata (a resumed animation's
    // frames equal an uninterrupted run's byte for byte). An image read with a DateTime keeps it.
    if (is_exr) spec.attribute("DateTime", "");
    // Names that do not match the channels (an image reshaped after reading) fall back to the defaults.
    if (is_exr && int(image.channel_names.size()) == image.channels) {
        spec.channelnames = image.channel_names;
        spec.alpha_channel = image.channel_index("A");
        spec.z_channel = image.channel_index("Depth.Z");
    }
    // A PNG keeps only text (its tEXt chunks): numbers there are written as text, or they were lost
    // (a render's PNG did not say its exposure).
    for (const auto& [name, value] : image.metadata.numbers) {
        if (is_exr) spec.attribute(name, OIIO::TypeDesc::DOUBLE, &value);
        else spec.attribute(name, shortest_number_text(value));
    }
    for (const auto& [name, value] : image.metadata.strings) spec.attribute(name, value);

    // Encoded in memory, then written by the one checked atomic writer (util/atomic_file.h): the
    // image libraries do not all report a short write (libpng through OIIO does not), so they never
    // touch the disk themselves.
    std::vector<unsigned char> encoded;
    OIIO::Filesystem::IOVecOutput memory(encoded);
    OIIO::Filesystem::IOProxy* proxy = &memory;
    auto out = OIIO::ImageOutput::create(path, proxy);
    if (!out) throw_file_error(path, "no writer for this format: " + OIIO::geterror());
    if (!out->supports("ioproxy") || !out->set_ioproxy(proxy))
        throw_file_error(path, std::string("the ") + out->format_name() + " writer cannot encode to memory");
    bool ok = out->open(path, spec);
    if (ok) {
        if (is_exr) {
            ok = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
        } else {
            std::vector<unsigned char> bytes(image.pixels.size());
            for (size_t i = 0; i < bytes.size(); ++i)
                bytes[i] = (unsigned char)std::lround(clamp(image.pixels[i], 0.0f, 1.0f) * 255.0f);
            ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
        }
    }
    ok = out->close() && ok;
    std::string why = out->geterror();
    if (!ok || encoded.empty())
        throw_file_error(path, "could not encode the image" + (why.empty() ? std::string() : ": " + why));
    return std::string(reinterpret_cast<const char*>(encoded.data()), encoded.size());
}

namespace {

// A display image's header: the radiance's, less its units (its pixels are display values now),
// with how they were made from it.
ImageMetadata display_metadata(const ImageMetadata& linear, float exposure_ev) {
    ImageMetadata m = linear;
    m.strings.erase("dynsky:units");
    m.numbers["dynsky:png_exposure_ev"] = exposure_ev;
    m.strings["dynsky:display_transform"] =
        "radiance x 2^dynsky:png_exposure_ev, ACES filmic curve (Narkowicz 2015), sRGB encoding";
    return m;
}

}  // namespace

Image tonemap_to_display(const Image& linear, float exposure_ev) {
    Image out(linear.width, linear.height, std::min(linear.channels, 3));
    float scale = std::exp2(exposure_ev);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x)
            for (int c = 0; c < out.channels; ++c)
                out.at(x, y, c) = linear_to_srgb(tonemap_aces(scale * linear.at(x, y, c)));
    out.metadata = display_metadata(linear.metadata, exposure_ev);
    return out;
}

Image tonemap_to_display(const Image& premultiplied, const Image& alpha, float exposure_ev) {
    if (alpha.empty()) return tonemap_to_display(premultiplied, exposure_ev);
    if (alpha.width != premultiplied.width || alpha.height != premultiplied.height || alpha.channels != 1)
        throw Error("tonemap_to_display: the alpha is not one channel of the image's size");
    Image out(premultiplied.width, premultiplied.height, 4);
    const float scale = std::exp2(exposure_ev);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            const float a = std::clamp(alpha.at(x, y, 0), 0.0f, 1.0f);
            for (int c = 0; c < 3; ++c) {
                const float straight = a > 0 ? premultiplied.at(x, y, std::min(c, premultiplied.channels - 1)) / a : 0;
                out.at(x, y, c) = a > 0 ? linear_to_srgb(tonemap_aces(scale * straight)) : 0.0f;
            }
            out.at(x, y, 3) = a;
        }
    out.metadata = display_metadata(premultiplied.metadata, exposure_ev);
    return out;
}

void check_extension(const std::string& option, const std::string& path, const std::string& ext) {
    if (file_extension(path) != ext) throw Error(option + " " + path + ": must name a " + ext + " file");
}

}  // namespace dynsky
