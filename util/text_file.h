// Text outputs (reports, manifests, CSV) written like images: to a temporary name in the same
// folder, then renamed, so a reader never sees half a file and a failed write leaves none.
#pragma once

#include <string>

namespace dynsky {

// Creates the parent folder if needed; throws dynsky::Error naming path if the write fails.
void write_text_atomic(const std::string& path, const std::string& text);

}  // namespace dynsky
