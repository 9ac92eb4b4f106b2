#include "util/suggest.h"

#include <algorithm>

namespace dynsky {

int edit_distance(const std::string& a, const std::string& b) {
    const size_t n = a.size(), m = b.size();
    std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
    for (size_t i = 0; i <= n; ++i) d[i][0] = int(i);
    for (size_t j = 0; j <= m; ++j) d[0][j] = int(j);
    for (size_t i = 1; i <= n; ++i)
        for (size_t j = 1; j <= m; ++j) {
            int cost = a[i - 1] == b[j - 1] ? 0 : 1;
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
                d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[n][m];
}

std::string closest_name(const std::string& word, const std::vector<std::string>& names) {
    if (word.empty()) return "";
    const int allowed = word.size() <= 4 ? 1 : word.size() <= 8 ? 2 : 3;
    std::string best;
    int best_distance = allowed + 1;
    size_t best_shared = 0;  // among equals, the name sharing the longer start with the word
    for (const std::string& name : names) {
        int d = edit_distance(word, name);
        size_t shared = 0;
        if (word.size() >= 3 && name.rfind(word, 0) == 0) d = std::min(d, 1);
        // A name the word starts with ("--outdir" for --out, "--sky-resolution" for --sky-res): a
        // longer spelling of it; the longest such name.
        else if (name.size() >= 5 && word.rfind(name, 0) == 0) d = std::min(d, allowed), shared = name.size();
        // A name ending in the word's own ("--sky-res" for --res): the same thing, qualified.
        else if (word.size() >= 5 && word.rfind("--", 0) == 0 && name.size() > word.size() &&
                 name.compare(name.size() - (word.size() - 1), word.size() - 1, word, 1) == 0)
            d = std::min(d, 1);
        if (d < best_distance || (d == best_distance && shared > best_shared))
            best = name, best_distance = d, best_shared = shared;
    }
    return best;
}

}  // namespace dynsky
