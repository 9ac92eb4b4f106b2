#include "fuzz/fuzz_support.h"

#include <OpenImageIO/imageio.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <typeinfo>

#include "util/image.h"
#include "util/image_input.h"

namespace dynsky::fuzz {

namespace fs = std::filesystem;

namespace {

// The folder is made on first use and removed when the process exits (after the fuzzer's last
// input), by the destructor of the object that names it.
struct TemporaryFolder {
    std::string path;
    TemporaryFolder() {
        const char* base = std::getenv("TMPDIR");
        path = std::string(base && *base ? base : "/tmp") + "/dynsky-fuzz-XXXXXX";
        if (!::mkdtemp(path.data())) {
            std::perror("dynsky fuzz: mkdtemp");
            std::abort();
        }
    }
    ~TemporaryFolder() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

const std::string& temporary_folder() {
    static const TemporaryFolder folder;
    return folder.path;
}

}  // namespace

void init_single_threaded() {
    static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 1);
}

std::string write_input(const uint8_t* data, size_t size, const std::string& name) {
    const std::string path = temporary_folder() + "/" + name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) {
        std::perror(("dynsky fuzz: " + path).c_str());
        std::abort();
    }
    return path;
}

long long header_values(const std::string& path) {
    // Only files dynsky's reader would hand to a decoder (util/image.h): the others it refuses first.
    if (!image_file_problem(path).empty()) return -1;
    ImageFileInput in(path);  // as read_image opens it
    if (!in) return -1;
    const OIIO::ImageSpec& spec = in->spec();
    return (long long)spec.width * spec.height * spec.nchannels * std::max(spec.depth, 1);
}

void unexpected_exception(const char* what) {
    std::fprintf(stderr, "dynsky fuzz: an exception other than dynsky::Error escaped: %s\n", what);
    std::abort();
}

}  // namespace dynsky::fuzz
