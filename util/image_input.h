#pragma once
// An OpenImageIO reader opened on an image file, the one way dynsky's readers open images.
//
// JPEGs are handed to OpenImageIO from memory without their APP13 segments (Photoshop resources
// and IPTC records, which dynsky never reads): OpenImageIO 2.4's IPTC decoder copies a record's
// declared length past the end of its segment, a heap over-read the fuzzer found on a corrupt
// photograph. Everything else (EXIF, ICC, the scans) is passed on byte for byte.

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>
#include <vector>

namespace dynsky {

class ImageFileInput {
  public:
    // Opens PATH; on failure get() is null and error() says OpenImageIO's reason (may be "").
    explicit ImageFileInput(const std::string& path);
    ImageFileInput(const ImageFileInput&) = delete;
    ImageFileInput& operator=(const ImageFileInput&) = delete;
    ~ImageFileInput();

    // Closes and opens the file again (some readers, WebP, cannot seek back to their first image).
    void reopen();

    OIIO::ImageInput* get() const { return in_.get(); }
    OIIO::ImageInput* operator->() const { return in_.get(); }
    explicit operator bool() const { return in_ != nullptr; }
    const std::string& error() const { return error_; }

  private:
    std::string path_;
    std::vector<unsigned char> bytes_;  // a JPEG's bytes as handed over; empty for other files
    std::unique_ptr<OIIO::Filesystem::IOMemReader> proxy_;
    std::unique_ptr<OIIO::ImageInput> in_;  // declared last: closed before the bytes it reads go
    std::string error_;
};

// A JPEG's bytes with its APP13 segments left out (the markers before the first scan walked as
// libjpeg walks them, skipping stray bytes); bytes that are not a JPEG come back unchanged.
std::vector<unsigned char> jpeg_without_app13(const std::vector<unsigned char>& jpeg);

}  // namespace dynsky
