#include "util/image_input.h"

#include <fstream>
#include <iterator>

#include "util/image.h"

namespace dynsky {

std::vector<unsigned char> jpeg_without_app13(const std::vector<unsigned char>& b) {
    const size_t n = b.size();
    if (n < 4 || b[0] != 0xFF || b[1] != 0xD8) return b;
    std::vector<unsigned char> out(b.begin(), b.begin() + 2);
    out.reserve(n);
    size_t i = 2;
    while (i < n) {
        // libjpeg skips stray bytes to the next FF: keep them, and find the segments it would.
        if (b[i] != 0xFF || i + 1 >= n || b[i + 1] == 0xFF) {
            out.push_back(b[i++]);
            continue;
        }
        const unsigned char m = b[i + 1];
        if (m == 0xDA || m == 0xD9) break;            // the scans (or the end): the rest as it is
        if (m == 0x01 || (m >= 0xD0 && m <= 0xD7)) {  // TEM, RSTn: no length
            out.insert(out.end(), b.begin() + long(i), b.begin() + long(i) + 2);
            i += 2;
            continue;
        }
        const size_t length = i + 3 < n ? (size_t(b[i + 2]) << 8 | b[i + 3]) : 0;
        const size_t end = std::min(n, i + 2 + std::max<size_t>(length, 2));
        if (m != 0xED) out.insert(out.end(), b.begin() + long(i), b.begin() + long(end));
        i = end;
    }
    out.insert(out.end(), b.begin() + long(std::min(i, n)), b.end());
    return out;
}

ImageFileInput::ImageFileInput(const std::string& path) : path_(path) {
    if (has_jpeg_signature(path)) {
        std::ifstream file(path, std::ios::binary);
        bytes_ = jpeg_without_app13(std::vector<unsigned char>((std::istreambuf_iterator<char>(file)),
                                                               std::istreambuf_iterator<char>()));
        proxy_ = std::make_unique<OIIO::Filesystem::IOMemReader>(bytes_.data(), bytes_.size());
    }
    reopen();
}

ImageFileInput::~ImageFileInput() { in_.reset(); }

void ImageFileInput::reopen() {
    in_.reset();
    error_.clear();
    // Colour as the file stores it: OpenImageIO would multiply unassociated alpha (PNG, most
    // TIFFs) into RGB, so a sky or photograph with alpha 0.5 came in at half its light. Alpha is
    // never radiance here; it stays a channel of its own.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    if (proxy_) {
        proxy_->seek(0);
        // By content, whatever the file's name: a JPEG named sky.exr is still read as a JPEG.
        in_ = OIIO::ImageInput::create("jpeg");
        OIIO::ImageSpec spec;
        void* proxy = proxy_.get();
        config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
        if (in_ && !(in_->set_ioproxy(proxy_.get()) && in_->open(path_, spec, config))) {
            error_ = in_->geterror();
            in_.reset();
        }
    } else {
        in_ = OIIO::ImageInput::open(path_, &config);
    }
    if (!in_ && error_.empty()) error_ = OIIO::geterror();
    (void)OIIO::geterror();
}

}  // namespace dynsky
