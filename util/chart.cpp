#include "util/chart.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "util/atomic_file.h"
#include "util/child_process.h"
#include "util/error.h"

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
    // The script goes on the command line (python3 -c): no script file to leave behind.
    TemporaryFile tmp(png);
    // Its messages are kept: on failure the last line says why (a full disk, no matplotlib), not a
    // traceback on the terminal. Run directly (no shell), so an interrupt stops it too.
    std::string said;
    const ChildResult run = run_program({"/usr/bin/python3", "-c", kChartScript, csv, tmp.path(), title, xlabel, ylabel,
                                         logy ? "1" : "0"},
                                        &said);
    if (!run.exited || run.exit_code != 0) {
        const int code = run.exited ? run.exit_code : -1;
        const std::string last = child_failure_reason(run, said);
        throw_file_error(png, "could not write the chart: python3 with matplotlib failed (exit " +
                                  std::to_string(code) + (last.empty() ? "" : ": " + last) + "); the data is in " +
                                  csv);
    }
    tmp.commit("matplotlib");
}

}  // namespace dynsky
