#include "util/data_path.h"

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <filesystem>
#include <system_error>

#include "util/error.h"

namespace dynsky {

namespace fs = std::filesystem;

std::vector<std::string> data_roots() {
    std::vector<std::string> roots;
    auto add = [&](const fs::path& p) {
        std::error_code ec;
        if (!p.empty() && fs::is_directory(p, ec)) roots.push_back(p.lexically_normal().string());
    };
    const char* env = std::getenv("DYNSKY_DATA");
    if (env && *env) {
        std::error_code ec;
        // A misspelt override was dropped without a word, and the installed data used instead.
        static std::once_flag warned;
        if (!fs::is_directory(env, ec))
            std::call_once(warned, [&] {
                std::fprintf(stderr, "dynsky: warning: DYNSKY_DATA=%s is not a folder: it is ignored\n", env);
            });
        add(fs::path(env));
    }
    std::error_code ec;
    fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) add(exe.parent_path().parent_path() / "share" / "dynsky");
    add(fs::path(DYNSKY_DATA_DIR));
    return roots;
}

std::optional<std::string> find_data_file(const std::string& relative) {
    for (const std::string& root : data_roots()) {
        fs::path p = fs::path(root) / relative;
        std::error_code ec;
        if (fs::exists(p, ec)) return p.string();
    }
    return std::nullopt;
}

std::string data_path(const std::string& relative) {
    if (auto p = find_data_file(relative)) return *p;
    std::string searched;
    for (const std::string& root : data_roots()) searched += (searched.empty() ? "" : ", ") + root;
    throw Error(relative + ": dynsky data file not found (searched " + (searched.empty() ? "nothing" : searched) +
                "; set DYNSKY_DATA to the dynsky source folder or its installed share/dynsky)");
}

std::string missing_user_path_text(const std::string& path) {
    if (path.empty() || fs::path(path).is_absolute()) return "no such file";
    std::string searched;
    for (const std::string& root : data_roots()) searched += (searched.empty() ? "" : ", ") + root;
    return "no such file here, nor in dynsky's data (searched " + (searched.empty() ? "nothing" : searched) +
           "; set DYNSKY_DATA to the dynsky source folder or its installed share/dynsky)";
}

std::string resolve_user_path(const std::string& path) {
    std::error_code ec;
    if (path.empty() || fs::path(path).is_absolute() || fs::exists(path, ec)) return path;
    if (auto p = find_data_file(path)) return *p;
    return path;
}

}  // namespace dynsky
