// Where dynsky's shipped data lives (Hosek-Wilkie tables, scenes, networks).
//
// Data roots, searched in order: $DYNSKY_DATA when set; the installed layout beside the program
// (PREFIX/bin/dynsky -> PREFIX/share/dynsky, found through /proc/self/exe, what `cmake --install`
// makes); the source tree recorded at build time (DYNSKY_DATA_DIR).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace dynsky {

// The data roots above that exist, in search order.
std::vector<std::string> data_roots();

// The first data root holding `relative`; nullopt when none does.
std::optional<std::string> find_data_file(const std::string& relative);

// find_data_file, or throws naming the relative path and the roots searched.
std::string data_path(const std::string& relative);

// A path given by the user (a scene, a model folder): as given when it exists there (or is
// absolute), else the shipped data file of that relative name (so `scenes/tower/tower.gltf` works
// from any folder), else as given (the caller's error then names it).
std::string resolve_user_path(const std::string& path);

// What to say of a user's path that resolve_user_path found nowhere: "no such file", and for a
// relative one where else it was looked for (the data roots, and how to name another).
std::string missing_user_path_text(const std::string& path);

}  // namespace dynsky
