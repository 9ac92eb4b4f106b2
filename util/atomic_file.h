// Every output file (images, reports, manifests, CSV, .npy arrays, videos) is written the same way:
// to a temporary name in the same folder, checked (every write and the close succeeded, the data
// reached the disk: fsync, the file is not empty), then renamed. So a reader never sees half a
// file, a failed write (full disk, file size limit) leaves none, and the error names the file.
//
// Temporaries are named .tmp-STEM-PID.EXT (the extension kept so tools that go by it, OIIO and
// ffmpeg, still work); a run killed with SIGKILL leaves one behind, which remove_stale_temporaries
// removes at the start of the next run in that folder.
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// Creates the parent folder if needed; throws dynsky::Error naming path if the write fails (the
// temporary removed, nothing under path changed).
void write_file_atomic(const std::string& path, const std::string& bytes);

// Several files that belong together (a render's EXR and its PNG): every one is written to its
// temporary before any is renamed into place, so a write failing (a full disk) changes none of
// them, and an earlier run's set stays whole.
void write_files_atomic(const std::vector<std::pair<std::string, std::string>>& files);

// Removes a file that says a folder's contents are complete (a timeline.json, a manifest.json)
// before a run replaces any of them, so that a run stopped midway never leaves it describing
// files it did not write. Nothing when absent; throws dynsky::Error naming path if it stays.
void remove_stale_marker(const std::string& path);

// The temporary name of this process for path (same folder): .tmp-STEM-PID.EXT.
std::string temporary_path(const std::string& path);

// The temporary of one output that another program writes (ffmpeg, python): removed when this goes
// out of scope uncommitted (an exception on the way), and by an interrupt (SIGINT, SIGTERM) while it
// exists (remove_active_temporary).
class TemporaryFile {
  public:
    explicit TemporaryFile(std::string target);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;
    const std::string& path() const { return path_; }
    // Checks it exists and is not empty (unless may_be_empty), syncs it to the disk, renames it to the
    // target. On failure removes it and throws naming the target, with `what` saying what wrote it.
    void commit(const std::string& what, bool may_be_empty = false);

  private:
    std::string given_, target_, path_;  // the name given, the file written (through links), the temporary
    bool committed_ = false;
    int slot_ = -1;                          // in the interrupt handler's list, or -1
    std::vector<std::string> made_folders_;  // made for it (outermost first): removed with it when empty
};

// How a run holds its output folder while it writes (an advisory lock on the folder, released
// when the run ends or is killed): exclusive, so that a second run into the same folder is refused
// at once (two runs each finished "successfully" with a folder of the other's files mixed into
// theirs: frames of two seeds under one manifest, a preview of another size beside a sky); shared
// for a render farm's frame tasks, which write disjoint frames of one animation side by side.
enum class FolderUse { exclusive, shared };

// An output folder made for a command's files: created (with its missing parents) on
// construction, and removed again at destruction when this made it and it is still empty (the
// command failed before writing anything: a full disk, a bad input found late), so a failure
// leaves no empty folders behind. Folders that hold finished work are never touched. Held (FolderUse)
// while it lives: another run holding it in a way that conflicts is an error naming the folder
// (where the file system has no such locks, nothing is held; on NFS the lock is seen only by runs
// on the same machine, as Linux keeps locks on folders on the client).
class OutputFolder {
  public:
    explicit OutputFolder(const std::string& path, FolderUse use = FolderUse::exclusive);
    ~OutputFolder();
    OutputFolder(const OutputFolder&) = delete;
    OutputFolder& operator=(const OutputFolder&) = delete;

  private:
    std::vector<std::string> created_;  // deepest last
    int lock_fd_ = -1;
};

// For the interrupt handler (cli/main.cpp): unlinks the temporary being written now, if any.
// Async-signal-safe.
void remove_active_temporary() noexcept;

// Removes the temporaries (our naming only) in folder whose process is gone; returns their names.
std::vector<std::string> remove_stale_temporaries(const std::string& folder);
// Only those of the outputs named by `stems` (file names without extension: frame_0003, timings):
// a render farm's task cleans up after its own killed attempt, never the temporaries of another
// task writing into the same folder from another machine (whose process ids mean nothing here).
std::vector<std::string> remove_stale_temporaries(const std::string& folder, const std::vector<std::string>& stems);

// Removes the files an earlier run left under these names before this run replaces any of them,
// so that a run stopped midway (Ctrl-C, a full disk) leaves only its own outputs, never a mix of two
// runs' (`compare`'s new images beside an earlier run's illuminance chart). Throws naming a file that
// cannot be removed. Only plain files go: missing and empty names, folders, links (written through,
// util/atomic_file.h) and devices are left as they are.
void remove_earlier_outputs(const std::vector<std::string>& files);

// Throws before any work if a file could not be written at `path` when the work is done: a folder
// of that name is in the way, a file stands where one of its folders would be made, or its
// folder is not writable. (A full disk is found only when writing.)
void check_output_file(const std::string& path);

// Throws before any work if an output would replace one of the inputs (the same file or folder,
// by canonical path; an output inside an input folder counts too). Empty names are ignored.
void check_outputs_are_not_inputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

// The same for the numbered images a command writes into `folder` (PREFIX_NNNN.exr and .png of each
// prefix, util/frame_names.h): a file named (an input, or another output such as a --stats CSV) that lies
// in that folder under such a name is refused. Empty names are ignored.
void check_numbered_outputs_spare(const std::string& folder, const std::vector<std::string>& prefixes,
                                  const std::vector<std::string>& files);

}  // namespace dynsky
