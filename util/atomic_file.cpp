#include "util/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>
#include <regex>

#include "util/error.h"
#include "util/frame_names.h"
#include "util/file_hash.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

std::string errno_text(int err) { return std::strerror(err); }

// fsync of a path opened read-only: flushes what another program (or OIIO) wrote. Returns errno or 0.
int sync_path(const fs::path& p, int flags) {
    int fd = ::open(p.c_str(), flags | O_CLOEXEC);
    if (fd < 0) return errno;
    int err = ::fsync(fd) == 0 ? 0 : errno;
    ::close(fd);
    // Folders of some file systems refuse fsync; the rename is still atomic there.
    return err == EINVAL || err == EBADF ? 0 : err;
}

// Where an output named `target` is written: through symbolic links to the file they name (the
// link kept, as `cp` and editors keep it); a device, FIFO or socket there is refused (renamed over,
// /dev/full or a FIFO became a plain file and the write "succeeded").
std::string output_target(const std::string& target) {
    std::error_code ec;
    fs::path p(target);
    for (int hops = 0; fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
        if (hops == 40) throw_file_error(target, "is a loop of symbolic links: give a file name");
        const fs::path to = fs::read_symlink(p, ec);
        if (ec) break;
        p = to.is_absolute() ? to : p.parent_path() / to;
    }
    const fs::file_status st = fs::status(p, ec);
    if (fs::exists(st) && !fs::is_regular_file(st) && !fs::is_directory(st))
        throw_file_error(target, std::string("is a ") +
                                     (fs::is_character_file(st) || fs::is_block_file(st) ? "device"
                                      : fs::is_fifo(st)                                  ? "FIFO"
                                                                                         : "special file") +
                                     ", not a file: outputs are written whole and renamed into place, which "
                                     "would replace it; give a file name");
    return p.string();
}

// The folders of `folder`'s path that do not exist yet, outermost first (what creating it makes).
std::vector<std::string> missing_folders(const fs::path& folder) {
    std::vector<std::string> missing;
    std::error_code ec;
    for (fs::path p = fs::absolute(folder, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec);
         p = p.parent_path()) {
        missing.insert(missing.begin(), p.string());
        if (p == p.parent_path()) break;
    }
    return missing;
}

// Removes the folders a failed command made (outermost first, as missing_folders lists them),
// innermost first, while they are empty: a failure leaves no empty folders behind.
void remove_empty_folders(const std::vector<std::string>& made) {
    std::error_code ec;
    for (auto it = made.rbegin(); it != made.rend(); ++it)
        if (fs::is_directory(*it, ec) && fs::is_empty(*it, ec) && !ec) fs::remove(*it, ec);
        else break;
}

// Makes the target's folder; returns the folders it made, outermost first.
std::vector<std::string> make_parent(const fs::path& target) {
    if (target.parent_path().empty()) return {};
    std::vector<std::string> made = missing_folders(target.parent_path());
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec) throw_file_error(target.string(), "cannot create its folder: " + ec.message());
    return made;
}

// Renames a complete, synced temporary into place (and syncs the folder so the name survives a crash).
void rename_into_place(const fs::path& tmp, const fs::path& target) {
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) {
        std::string why = ec.message();  // before the clean-up's own code replaces it ("Success")
        if (fs::is_directory(target, ec)) why = "a folder of that name is in the way";
        fs::remove(tmp, ec);
        throw_file_error(target.string(), "could not write the file: " + why);
    }
    sync_path(target.parent_path().empty() ? fs::path(".") : target.parent_path(), O_RDONLY | O_DIRECTORY);
}

// The temporaries being written now, for remove_active_temporary: a few slots (a render writes its
// EXR and PNG side by side, committed together); a writer finding none free is simply not
// registered.
constexpr int kActiveSlots = 4;
char g_active[kActiveSlots][4096];
std::atomic<bool> g_active_set[kActiveSlots], g_active_busy[kActiveSlots];

int register_active(const std::string& path) {
    if (path.size() >= sizeof g_active[0]) return -1;
    for (int k = 0; k < kActiveSlots; ++k) {
        bool expected = false;
        if (!g_active_busy[k].compare_exchange_strong(expected, true)) continue;
        std::memcpy(g_active[k], path.c_str(), path.size() + 1);
        g_active_set[k] = true;
        return k;
    }
    return -1;
}

void unregister_active(int k) {
    g_active_set[k] = false;
    g_active_busy[k] = false;
}

// Writes bytes into a temporary made for `path` (named after it in errors), synced; not committed.
void fill_temporary(const TemporaryFile& tmp, const std::string& path, const std::string& bytes) {
    int fd = ::open(tmp.path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) throw_file_error(path, "could not write the file: " + errno_text(errno));
    int err = 0;
    for (size_t done = 0; done < bytes.size() && !err;) {
        ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n > 0) done += size_t(n);
        else if (n < 0 && errno != EINTR) err = errno;
        else if (n == 0) err = EIO;
    }
    if (!err && ::fsync(fd) != 0 && errno != EINVAL) err = errno;
    if (::close(fd) != 0 && !err) err = errno;
    if (err)
        throw_file_error(path,
                         "could not write the file (" + std::to_string(bytes.size()) + " bytes): " + errno_text(err));
}

}  // namespace

void remove_active_temporary() noexcept {
    for (int k = 0; k < kActiveSlots; ++k)
        if (g_active_set[k]) ::unlink(g_active[k]);
}

// The temporary lies beside the file written (a link's target), named after the name given: its
// extension is what tools (ffmpeg, matplotlib) take the format from, and a link "animation.mp4" to
// "anim" made ffmpeg fail on ".tmp-anim-PID".
TemporaryFile::TemporaryFile(std::string target)
    : given_(target),
      target_(output_target(target)),
      path_((fs::path(target_).parent_path() / fs::path(temporary_path(given_)).filename()).string()) {
    made_folders_ = make_parent(fs::path(target_));
    slot_ = register_active(path_);
}

TemporaryFile::~TemporaryFile() {
    std::error_code ec;
    if (!committed_) {
        fs::remove(path_, ec);
        // And the folders made for it, where nothing else came into them: a write that failed (a
        // full disk) left `render -o new/folder/x.exr`'s folders behind, empty.
        remove_empty_folders(made_folders_);
    }
    if (slot_ >= 0) unregister_active(slot_);
}

void TemporaryFile::commit(const std::string& what, bool may_be_empty) {
    const fs::path tmp(path_);
    std::error_code ec;
    auto fail = [&](const std::string& why) {
        fs::remove(tmp, ec);
        throw_file_error(given_, "could not write the file: " + what + ": " + why);
    };
    if (!fs::is_regular_file(tmp, ec)) fail("it wrote no file");
    if ((fs::file_size(tmp, ec) == 0 && !may_be_empty) || ec) fail("it wrote an empty file");
    if (int err = sync_path(tmp, O_RDONLY)) fail(errno_text(err));
    committed_ = true;
    rename_into_place(tmp, fs::path(target_));
}

std::string temporary_path(const std::string& path) {
    fs::path target(path);
    std::string stem = target.stem().string();
    const std::string pid = std::to_string(::getpid()), ext = target.extension().string();
    // A name may have 255 bytes: the temporary's 6 + pid more made valid long names (82 CJK
    // characters) fail after the whole render. Too long, the stem is cut at a character's start and
    // a hash of the whole keeps temporaries of different names apart.
    constexpr size_t kNameMax = 255;
    const size_t room = kNameMax - std::min(kNameMax, 6 + pid.size() + ext.size());
    if (stem.size() > room && room > 9) {
        size_t cut = room - 9;
        while (cut > 0 && (static_cast<unsigned char>(stem[cut]) & 0xC0) == 0x80) --cut;
        stem = stem.substr(0, cut) + "~" + hex64(fnv1a(stem.data(), stem.size())).substr(0, 8);
    }
    return (target.parent_path() / (".tmp-" + stem + "-" + pid + ext)).string();
}

OutputFolder::OutputFolder(const std::string& path, FolderUse use) {
    created_ = missing_folders(path);
    std::error_code ec;
    fs::create_directories(path, ec);
    if (ec) throw_file_error(path, "cannot create the output folder: " + ec.message());
    // Not inherited by children (ffmpeg, the chart script): a killed run's lock goes with it.
    lock_fd_ = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (lock_fd_ >= 0 && ::flock(lock_fd_, (use == FolderUse::shared ? LOCK_SH : LOCK_EX) | LOCK_NB) != 0) {
        const int err = errno;
        ::close(lock_fd_);
        lock_fd_ = -1;
        if (err == EWOULDBLOCK)
            throw_file_error(path,
                             "another dynsky run is writing into this folder now: wait for it to finish, or "
                             "choose another output folder");
        // Anything else (a file system without such locks): written unheld, as before.
    }
}

OutputFolder::~OutputFolder() {
    remove_empty_folders(created_);
    // Released last: a run let in before the empty folder went would write into a folder re-made unheld.
    if (lock_fd_ >= 0) ::close(lock_fd_);
}

void check_output_file(const std::string& path) {
    if (path.empty()) return;
    const fs::path target(output_target(path));
    std::error_code ec;
    if (fs::is_directory(target, ec)) throw_file_error(path, "a folder of that name is in the way");
    // The nearest existing folder above it must be a folder, and writable.
    fs::path up = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    while (!fs::exists(up, ec) && up.has_parent_path() && up.parent_path() != up) up = up.parent_path();
    if (fs::exists(up, ec) && !fs::is_directory(up, ec))
        throw_file_error(path, "cannot create its folder: " + up.string() + " is a file");
    if (fs::is_directory(up, ec) && ::access(up.c_str(), W_OK) != 0)
        throw_file_error(path, "cannot write into " + up.string() + ": " + std::strerror(errno));
}

void remove_earlier_outputs(const std::vector<std::string>& files) {
    for (const std::string& f : files) {
        if (f.empty()) continue;
        std::error_code ec;
        const fs::file_status st = fs::symlink_status(f, ec);
        if (!fs::is_regular_file(st)) continue;  // missing; a folder, link or device is the user's
        if (!fs::remove(f, ec) || ec)
            throw_file_error(f, "could not remove the earlier run's file before writing this run's" +
                                    (ec ? ": " + ec.message() : std::string()));
    }
}

void remove_stale_marker(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return;
    if (!std::filesystem::remove(path, ec) || ec)
        throw_file_error(path, "could not remove it before replacing the files it describes" +
                                   (ec ? ": " + ec.message() : std::string()));
}

void write_file_atomic(const std::string& path, const std::string& bytes) { write_files_atomic({{path, bytes}}); }

void write_files_atomic(const std::vector<std::pair<std::string, std::string>>& files) {
    std::vector<std::unique_ptr<TemporaryFile>> temporaries;
    try {
        for (const auto& [path, bytes] : files) {
            temporaries.push_back(std::make_unique<TemporaryFile>(path));
            fill_temporary(*temporaries.back(), path, bytes);
        }
        for (size_t k = 0; k < files.size(); ++k) temporaries[k]->commit("the write", files[k].second.empty());
    } catch (...) {
        // The last made first, so that the first's folders are empty when it goes.
        while (!temporaries.empty()) temporaries.pop_back();
        throw;
    }
}

namespace {

std::vector<std::string> remove_temporaries(const std::string& folder, const std::vector<std::string>* stems) {
    std::vector<std::string> removed;
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return removed;
    static const std::regex naming(R"(^\.tmp-(.*)-([0-9]+)(\.[A-Za-z0-9]+)?$)");
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        const std::string name = entry.path().filename().string();
        std::smatch m;
        if (!std::regex_match(name, m, naming)) continue;
        if (stems && std::find(stems->begin(), stems->end(), m[1].str()) == stems->end()) continue;
        long pid = std::strtol(m[2].str().c_str(), nullptr, 10);
        // Alive (ours, or another run writing here now): kill(pid, 0) succeeds or is refused.
        if (pid > 0 && pid == long(::getpid())) continue;
        if (pid > 0 && pid <= 4194304 && (::kill(pid_t(pid), 0) == 0 || errno == EPERM)) continue;
        if (fs::remove(entry.path(), ec)) removed.push_back(name);
    }
    return removed;
}

}  // namespace

std::vector<std::string> remove_stale_temporaries(const std::string& folder) {
    return remove_temporaries(folder, nullptr);
}

std::vector<std::string> remove_stale_temporaries(const std::string& folder, const std::vector<std::string>& stems) {
    return remove_temporaries(folder, &stems);
}

void check_outputs_are_not_inputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
    for (const std::string& in : inputs) {
        std::error_code ec;
        if (in.empty() || !fs::exists(in, ec)) continue;
        const fs::path input = fs::weakly_canonical(in, ec);
        const bool folder = fs::is_directory(input, ec);
        for (const std::string& out : outputs) {
            if (out.empty()) continue;
            const fs::path output = fs::weakly_canonical(out, ec);
            bool same = output == input || (fs::exists(output, ec) && fs::equivalent(output, input, ec));
            if (same) throw_file_error(out, "is also an input (" + in + "); refusing to overwrite it");
            if (folder) {
                auto rel = output.lexically_relative(input);
                if (!rel.empty() && *rel.begin() != "..")
                    throw_file_error(out, "is inside the input folder " + in + "; refusing to write there");
            }
        }
    }
}

void check_numbered_outputs_spare(const std::string& folder, const std::vector<std::string>& prefixes,
                                  const std::vector<std::string>& files) {
    std::error_code ec;
    const fs::path out = fs::weakly_canonical(fs::absolute(folder), ec).lexically_normal();
    auto refuse = [&](const std::string& file, const std::string& prefix) {
        throw_file_error(file, "has the name of one of the files this command writes into " + folder + " (" + prefix +
                                   "_NNNN); refusing to overwrite it: move it or choose another --out");
    };
    // Every numbered output is an image: PREFIX_NNNN.exr or .png.
    auto numbered = [&](const fs::path& name, const std::string& prefix) {
        const std::string ext = name.extension().string();
        return (ext == ".exr" || ext == ".png") && numbered_index(name.filename().string(), prefix).has_value();
    };
    for (const std::string& file : files) {
        if (file.empty()) continue;
        // The name as given, in its folder (a link named frame_0000.exr is written through).
        const fs::path given = fs::absolute(file);
        const fs::path parent = fs::weakly_canonical(given.parent_path(), ec).lexically_normal();
        if (parent == out || (fs::exists(parent, ec) && fs::exists(out, ec) && fs::equivalent(parent, out, ec)))
            for (const std::string& prefix : prefixes)
                if (numbered(given, prefix)) refuse(file, prefix);
        // And any numbered name in the folder that is this file (a link to it, a hard link).
        if (!fs::exists(file, ec) || !fs::is_directory(out, ec)) continue;
        for (const auto& e : fs::directory_iterator(out, ec))
            for (const std::string& prefix : prefixes)
                if (numbered(e.path(), prefix) && fs::equivalent(e.path(), file, ec))
                    refuse(e.path().string() + " (" + file + ")", prefix);
    }
}

}  // namespace dynsky
