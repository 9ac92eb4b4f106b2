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
colours = {}
for c in range(1, len(head)):
    if head[c] == 'boundary':
        for r in data:
            if r[c] > 0.5: ax.axvline(r[0], color='0.8', lw=6, zorder=0)
        continue
    # A clear/cloudy pair (compare's columns) shares a colour, the clear one dashed.
    key = head[c].replace('cloudy', '').replace('clear', '')
    colour = colours.setdefault(key, 'C%d' % (len(colours) % 10))
    dashed = 'clear' in head[c] and 'cloudy' not in head[c]
    ax.plot(x, [r[c] for r in data], marker='o', ms=3, label=head[c], color=colour, ls='--' if dashed else '-')
if logy == '1':
    ax.set_yscale('log')
    # Within three decades a tick at 1, 2, 3 and 5 of each, labelled as plain numbers: one labelled
    # tick (10^3) was all a chart from 250 to 6000 showed.
    values = [r[c] for r in data for c in range(1, len(head)) if head[c] != 'boundary' and r[c] > 0]
    if values and max(values) / min(values) < 1000:
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
        ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1, 2, 3, 5)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: '%g' % v))
        ax.yaxis.set_minor_formatter(NullFormatter())
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
