#include "util/atomic_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "util/error.h"

namespace dynsky {

void write_file_atomic(const std::string& path, const std::string& bytes) {
    namespace fs = std::filesystem;
    fs::path target(path);
    std::error_code ec;
    if (!target.parent_path().empty()) fs::create_directories(target.parent_path(), ec);
    fs::path tmp = target.parent_path() / (".tmp-" + target.filename().string() + "-" + std::to_string(::getpid()));
    {
        std::ofstream f(tmp, std::ios::binary);
        f.write(bytes.data(), std::streamsize(bytes.size()));
        f.flush();
        if (!f) {
            fs::remove(tmp, ec);
            throw_file_error(path, "could not write the file");
        }
    }
    fs::rename(tmp, target, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw_file_error(path, "could not write the file");
    }
}

}  // namespace dynsky
