#include "util/chart.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "util/shell.h"

namespace dynsky {

namespace fs = std::filesystem;

namespace {

const char* kChartScript = R"PY(
import csv, sys
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt
path, out, title, xlabel, ylabel, logy = sys.argv[1:7]
rows = list(csv.reader(open(path)))
head, data = rows[0], [[float(v) for v in r] for r in rows[1:]]
x = [r[0] for r in data]
fig, ax = plt.subplots(figsize=(11, 4.5), dpi=110)
for c in range(1, len(head)):
    if head[c] == 'boundary':
        for r in data:
            if r[c] > 0.5: ax.axvline(r[0], color='0.8', lw=6, zorder=0)
        continue
    ax.plot(x, [r[c] for r in data], marker='o', ms=3, label=head[c])
if logy == '1': ax.set_yscale('log')
ax.set_title(title); ax.set_xlabel(xlabel); ax.set_ylabel(ylabel); ax.grid(alpha=0.3)
# The legend beside the plot, never over the lines.
ax.legend(fontsize=8, loc='upper left', bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
fig.tight_layout(); fig.savefig(out)
)PY";

}  // namespace

void make_line_chart(const std::string& csv, const std::string& png, const std::string& title,
                     const std::string& xlabel, const std::string& ylabel, bool logy) {
    std::string script = (fs::path(png).parent_path() / ".chart.py").string();
    std::ofstream(script) << kChartScript;
    std::string tmp = (fs::path(png).parent_path() / ".partial.chart.png").string();
    std::string cmd = "/usr/bin/python3 " + shell_quote(script) + " " + shell_quote(csv) + " " + shell_quote(tmp) +
                      " " + shell_quote(title) + " " + shell_quote(xlabel) + " " + shell_quote(ylabel) +
                      (logy ? " 1" : " 0");
    int rc = std::system(cmd.c_str());
    fs::remove(script);
    if (rc != 0) {
        fs::remove(tmp);
        std::fprintf(stderr, "dynsky: warning: matplotlib chart %s failed (exit %d); the data is in %s\n", png.c_str(),
                     rc, csv.c_str());
        return;
    }
    fs::rename(tmp, png);
}

}  // namespace dynsky
