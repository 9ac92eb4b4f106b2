// "Did you mean ...?": the known name closest to a misspelt one (edit distance with transpositions).
#pragma once

#include <string>
#include <vector>

namespace dynsky {

// Optimal-string-alignment distance: insertions, deletions, substitutions and swaps of neighbours.
int edit_distance(const std::string& a, const std::string& b);

// The name of `names` nearest to word, if near enough to be a slip (at most 1 edit for words of up
// to 4 letters, 2 up to 8, then 3), else "". A word that begins a name also matches ("rend").
std::string closest_name(const std::string& word, const std::vector<std::string>& names);

}  // namespace dynsky
