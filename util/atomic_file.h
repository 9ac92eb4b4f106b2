// Files other than images (reports, manifests, CSV, .npy arrays) written like images: to a
// temporary name in the same folder, then renamed, so a reader never sees half a file and a
// failed write leaves none. The bytes are written as given (binary mode).
#pragma once

#include <string>

namespace dynsky {

// Creates the parent folder if needed; throws dynsky::Error naming path if the write fails.
void write_file_atomic(const std::string& path, const std::string& bytes);

}  // namespace dynsky
