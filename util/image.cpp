#include "util/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "util/atomic_file.h"
#include "util/color.h"
#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

std::string file_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

int Image::channel_index(const std::string& name) const {
    for (size_t i = 0; i < channel_names.size(); ++i)
        if (channel_names[i] == name) return int(i);
    return -1;
}

Image read_image(const std::string& path) {
    if (!fs::exists(path)) throw_file_error(path, "no such file");
    if (fs::is_directory(path)) throw_file_error(path, "is a directory, not an image");
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string why = OIIO::geterror();
        throw_file_error(path, "not a readable image" + (why.empty() ? std::string() : " (" + why + ")"));
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) throw_file_error(path, "image has no pixels");
    Image image(spec.width, spec.height, spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data())) {
        std::string why = in->geterror();
        throw_file_error(path, "could not decode pixels (truncated or corrupt?)" +
                                   (why.empty() ? std::string() : ": " + why));
    }
    for (const std::string& name : spec.channelnames) image.channel_names.push_back(name);
    for (const auto& p : spec.extra_attribs) {
        std::string name = p.name().string();
        if (p.type() == OIIO::TypeDesc::STRING) image.metadata.strings[name] = p.get_string();
        else if (p.type() == OIIO::TypeDesc::FLOAT || p.type() == OIIO::TypeDesc::DOUBLE ||
                 p.type() == OIIO::TypeDesc::INT)
            image.metadata.numbers[name] = p.get_float();
    }
    // Double attributes lose precision through get_float(); re-read them exactly.
    for (auto& [name, value] : image.metadata.numbers) {
        double d;
        if (spec.getattribute(name, OIIO::TypeDesc::DOUBLE, &d)) value = d;
    }
    in->close();
    return image;
}

void write_image(const std::string& path, const Image& image) {
    if (image.empty()) throw_file_error(path, "refusing to write an empty image");
    std::string ext = file_extension(path);
    bool is_exr = ext == ".exr";
    bool is_ldr = ext == ".png" || ext == ".jpg" || ext == ".jpeg";
    if (!is_exr && !is_ldr) throw_file_error(path, "unsupported output extension '" + ext + "' (use .exr or .png)");

    OIIO::ImageSpec spec(image.width, image.height, image.channels,
                         is_exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (is_exr) spec.attribute("compression", "zip");
    // Names that do not match the channels (an image reshaped after reading) fall back to the defaults.
    if (is_exr && int(image.channel_names.size()) == image.channels) {
        spec.channelnames = image.channel_names;
        spec.alpha_channel = image.channel_index("A");
        spec.z_channel = image.channel_index("Depth.Z");
    }
    for (const auto& [name, value] : image.metadata.numbers) spec.attribute(name, OIIO::TypeDesc::DOUBLE, &value);
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
    write_file_atomic(path, std::string(reinterpret_cast<const char*>(encoded.data()), encoded.size()));
}

Image tonemap_to_display(const Image& linear, float exposure_ev) {
    Image out(linear.width, linear.height, std::min(linear.channels, 3));
    float scale = std::exp2(exposure_ev);
    for (int y = 0; y < linear.height; ++y)
        for (int x = 0; x < linear.width; ++x)
            for (int c = 0; c < out.channels; ++c)
                out.at(x, y, c) = linear_to_srgb(tonemap_aces(scale * linear.at(x, y, c)));
    out.metadata = linear.metadata;
    return out;
}

}  // namespace dynsky
